#version 430 core
// Swept mesh M_k seen from C (worker/glsl_sweep.cc, docs/sweep.md): world position (relative to
// the origin) and face index of the nearest surface, and, in the same pass, each neighbour's
// image reprojected through that surface (sweep_reproject.glsl): the outputs of the fragment
// that wins the depth test are those of the surface C sees. The targets are cleared to
// w = -1 (no surface; faces are < 2^24, exact in float) and to m = 0 (invalid).
in vec3 gs_world;

layout(location = 0) out vec4 o_world;
layout(location = 1) out vec4 o_reprojected[NEIGHBOURS];

uniform int u_pixel_offset;  // C's pixel x is at framebuffer column x + u_pixel_offset

#include "sweep_reproject.glsl"

void main() {
  o_world = vec4(gs_world, float(gl_PrimitiveID));
  ivec2 pixel = ivec2(gl_FragCoord.xy) - ivec2(u_pixel_offset, 0);
  float centred = texelFetch(u_image, pixel, 0).r - 0.5;
  for (int j = 0; j < NEIGHBOURS; ++j) {
    o_reprojected[j] = Reproject(j, gs_world, gl_Layer, centred);
  }
}
