// A cluster of the light cloud's transfer as the renderer uploads it (std430: 16 bytes):
// where its terms start, its zone's first cloud light and light count, and D_c.
struct Cluster {
    uint offset;
    uint first_light;
    uint lights;
    uint vectors;
};
