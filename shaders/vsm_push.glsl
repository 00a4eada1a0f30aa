layout(push_constant) uniform VsmPush {
    uint light;
    uint layer;
} pc;
