// A cluster of the light cloud's transfer as the renderer uploads it (std430: 16 bytes):
// where its terms start, its zone's first column and column count (a column: one emission
// function of one cloud light), and D_c.
struct Cluster {
    uint offset;
    uint first_column;
    uint columns;
    uint vectors;
};
