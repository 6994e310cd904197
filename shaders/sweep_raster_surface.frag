#version 430 core
// Swept mesh M_k seen from C (sweep/glsl_sweep.cc, docs/design/sweep.md): camera z and face index of
// the nearest surface, 8 bytes a fragment. World positions and reprojections are computed
// afterwards, once per pixel, by sweep_reproject.comp: GPUs built for compute (H100) have few
// raster output units, and writing them here (48 bytes a fragment, overdrawn ones included)
// made the raster stage most of the kernel there. The target is cleared to (0, -1): no surface.
in float gs_depth;

layout(location = 0) out vec2 o_surface;

void main() { o_surface = vec2(gs_depth, float(gl_PrimitiveID)); }
