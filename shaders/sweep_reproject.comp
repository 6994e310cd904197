#version 430 core
// Per pixel of C and offset of the batch (sweep/glsl_sweep.cc, docs/design/sweep.md): the world
// position of the surface C sees (on C's ray through the pixel centre, at the camera z of
// sweep_raster_surface.frag) with its face, and each neighbour's image reprojected through it
// (sweep_reproject.glsl). Runs over the padded width: outside the image, and where C sees no
// surface, it writes w = -1 (no surface) and m = 0 (invalid), so no clears are needed.
layout(local_size_x = 8, local_size_y = 8) in;

uniform sampler2DArray u_surface;  // (camera z, face), x at x + u_pixel_offset
layout(binding = 0, rgba32f) writeonly uniform image2DArray o_world;
layout(binding = 1, rgba32f) writeonly uniform image2DArray o_reprojected[NEIGHBOURS];

uniform ivec2 u_size;         // padded width, height
uniform int u_layers;         // offsets in the batch
uniform int u_pixel_offset;   // C's pixel x is at column x + u_pixel_offset
uniform int u_image_width;
uniform vec3 u_center;        // C's centre, relative to the origin
uniform mat3 u_pixel_to_ray;  // R_C^T K^-1: pixel (u, v, 1) -> ray direction per unit camera z
uniform bool u_write_world;   // the first group of neighbours writes the world positions

#include "sweep_reproject.glsl"

void main() {
  ivec3 at = ivec3(gl_GlobalInvocationID);
  if (at.x >= u_size.x || at.y >= u_size.y || at.z >= u_layers) return;
  int x = at.x - u_pixel_offset;
  vec2 surface = x >= 0 && x < u_image_width ? texelFetch(u_surface, at, 0).rg : vec2(0.0, -1.0);
  if (surface.y < 0.0) {
    if (u_write_world) imageStore(o_world, at, vec4(0.0, 0.0, 0.0, -1.0));
    for (int j = 0; j < NEIGHBOURS; ++j) imageStore(o_reprojected[j], at, vec4(0.0));
    return;
  }
  vec3 world = u_center + surface.x * (u_pixel_to_ray * vec3(float(x) + 0.5, float(at.y) + 0.5, 1.0));
  if (u_write_world) imageStore(o_world, at, vec4(world, surface.y));
  float centred = texelFetch(u_image, ivec2(x, at.y), 0).r - 0.5;
  for (int j = 0; j < NEIGHBOURS; ++j) {
    imageStore(o_reprojected[j], at, Reproject(j, world, at.z, centred));
  }
}
