#version 430 core
// NCC, first pass (docs/design/sweep.md "NCC"): Gaussian sums along image rows of
// m, m I, m J, m I^2, m J^2, m I J (I, J shifted by -0.5) from the reprojection (layer u_layer of
// the batch's reprojection array, written by sweep_reproject.comp).
// Written transposed when TRANSPOSED (the column pass then reads rows again: contiguous memory,
// which matters on CPU rasterizers), in both cases padded by RADIUS zeros along the columns.
layout(local_size_x = LOCAL_X, local_size_y = LOCAL_Y) in;

struct Sums {
  vec4 a;
  vec2 b;
};

// imageLoad rather than texelFetch: cheaper on llvmpipe, the same on GPUs.
layout(binding = 2, rgba32f) readonly uniform image2DArray u_reprojected;  // x at x + RADIUS
layout(binding = 0, rgba32f) writeonly uniform image2D o_sums0;
layout(binding = 1, rg32f) writeonly uniform image2D o_sums1;

uniform ivec2 u_size;  // C's image size
uniform int u_layer;

int g_row;
int g_first;  // first output column of this invocation

bool BeginLine() {
  g_row = int(gl_GlobalInvocationID.y);
  g_first = int(gl_GlobalInvocationID.x) * BLOCK;
  return g_row < u_size.y && g_first < u_size.x;
}

Sums LoadSample(int i) {
  vec3 s = imageLoad(u_reprojected, ivec3(g_first + i, g_row, u_layer)).xyz;
  return Sums(vec4(s, s.y * s.y), vec2(s.z * s.z, s.y * s.z));
}

void FinishOutput(int o, Sums sums) {
  int x = g_first + o;
  if (x >= u_size.x) return;
#if TRANSPOSED
  ivec2 at = ivec2(g_row + RADIUS, x);
#else
  ivec2 at = ivec2(x, g_row + RADIUS);
#endif
  imageStore(o_sums0, at, sums.a);
  imageStore(o_sums1, at, vec4(sums.b, 0.0, 0.0));
}

#include "sweep_blur.glsl"

#if TILED
// One output per invocation, a work group per LOCAL_X outputs of a row (LOCAL_Y = 1): the
// group's LOCAL_X + 2 RADIUS samples are loaded once into shared memory, so each sample is
// read from the image about once instead of 2 RADIUS + 1 times (image loads of RGBA32F are
// what the loop version waits on on a GPU). The same taps in the same order: the same sums.
shared vec4 s_a[LOCAL_X + 2 * RADIUS];
shared vec2 s_b[LOCAL_X + 2 * RADIUS];

void main() {
  g_row = int(gl_GlobalInvocationID.y);
  if (g_row >= u_size.y) return;  // the whole group: one row
  int group_first = int(gl_WorkGroupID.x) * LOCAL_X;
  int local_x = int(gl_LocalInvocationID.x);
  for (int i = local_x; i < LOCAL_X + 2 * RADIUS; i += LOCAL_X) {
    vec3 s = imageLoad(u_reprojected, ivec3(group_first + i, g_row, u_layer)).xyz;
    s_a[i] = vec4(s, s.y * s.y);
    s_b[i] = vec2(s.z * s.z, s.y * s.z);
  }
  barrier();
  g_first = group_first + local_x;
  if (g_first >= u_size.x) return;
  Sums acc = ZeroSums();
  for (int i = 0; i <= 2 * RADIUS; ++i) {
    Tap(acc, u_weights[i], Sums(s_a[local_x + i], s_b[local_x + i]));
  }
  FinishOutput(0, acc);
}
#endif
