#version 430 core
// Shadow map of M_k from a neighbour: camera z of the nearest surface (cleared to +infinity).
in float gs_depth;

layout(location = 0) out float o_depth;

void main() { o_depth = gs_depth; }
