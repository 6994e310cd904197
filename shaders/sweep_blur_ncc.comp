#version 430 core
// NCC, second pass (docs/design/sweep.md "NCC"): Gaussian sums along columns of the row pass's sums,
// then the weighted NCC per pixel, in double as the reference:
//   W = G(m), mu_I = G(mI)/W, var_I = G(mI^2)/W - mu_I^2, likewise J, cov = G(mIJ)/W - mu_I mu_J,
//   NCC = cov / sqrt(var_I var_J) clamped to [-1, 1],
// undefined (UNDEFINED_NCC) where m = 0 at the pixel, W < min_window_weight, or a variance is at
// most max(min_texture_variance, 1e-5 x its mean square). Written to layer u_ncc_layer of the
// batch's NCC array (not padded).
#if TILED
layout(local_size_x = TILE_X, local_size_y = TILE_Y) in;
#else
layout(local_size_x = LOCAL_X, local_size_y = LOCAL_Y) in;
#endif

struct Sums {
  vec4 a;
  vec2 b;
};

layout(binding = 1, rgba32f) readonly uniform image2D u_sums0;  // row pass: (W, S_I, S_J, S_II)
layout(binding = 2, rg32f) readonly uniform image2D u_sums1;    // row pass: (S_JJ, S_IJ)
layout(binding = 3, rgba32f) readonly uniform image2DArray u_reprojected;  // mask at the pixel
layout(binding = 0, r32f) writeonly uniform image2DArray o_ncc;

uniform ivec2 u_size;  // C's image size
uniform int u_layer;      // the offset's layer b in the reprojection array
uniform int u_ncc_layer;  // b * neighbours + j in the NCC array
uniform double u_min_window_weight;
uniform double u_min_texture_variance;

const double kVarianceFloor = 1e-5LF;  // relative to the mean square: float round-off

int g_column;
int g_first;  // first output row of this invocation

bool BeginLine() {
#if TRANSPOSED
  g_first = int(gl_GlobalInvocationID.x) * BLOCK;
  g_column = int(gl_GlobalInvocationID.y);
#else
  g_column = int(gl_GlobalInvocationID.x);
  g_first = int(gl_GlobalInvocationID.y) * BLOCK;
#endif
  return g_column < u_size.x && g_first < u_size.y;
}

Sums LoadSample(int i) {
#if TRANSPOSED
  ivec2 at = ivec2(g_first + i, g_column);
#else
  ivec2 at = ivec2(g_column, g_first + i);
#endif
  return Sums(imageLoad(u_sums0, at), imageLoad(u_sums1, at).xy);
}

float Ncc(Sums sums, float mask) {
  float w = sums.a.x;
  if (!(mask > 0.0) || !(double(w) >= u_min_window_weight)) return UNDEFINED_NCC;
  double inv_w = 1.0LF / double(w);
  double mean_i = double(sums.a.y) * inv_w;
  double mean_j = double(sums.a.z) * inv_w;
  double square_i = double(sums.a.w) * inv_w;
  double square_j = double(sums.b.x) * inv_w;
  double var_i = square_i - mean_i * mean_i;
  double var_j = square_j - mean_j * mean_j;
  double floor_i = max(u_min_texture_variance, kVarianceFloor * square_i);
  double floor_j = max(u_min_texture_variance, kVarianceFloor * square_j);
  if (!(var_i > floor_i && var_j > floor_j)) return UNDEFINED_NCC;
  double cov = double(sums.b.y) * inv_w - mean_i * mean_j;
  return float(clamp(cov / sqrt(var_i * var_j), -1.0LF, 1.0LF));
}

void FinishOutput(int o, Sums sums) {
  int y = g_first + o;
  if (y >= u_size.y) return;
  float mask = imageLoad(u_reprojected, ivec3(g_column + RADIUS, y, u_layer)).x;
  imageStore(o_ncc, ivec3(g_column, y, u_ncc_layer), vec4(Ncc(sums, mask), 0.0, 0.0, 0.0));
}

#include "sweep_blur.glsl"

#if TILED
// One output per invocation, a work group per TILE_X x TILE_Y outputs: the TILE_Y + 2 RADIUS
// rows of sums above them are loaded once into shared memory ((TILE_Y + 2 RADIUS) / TILE_Y
// image loads per output instead of 2 RADIUS + 1). The same taps in the same order: the same
// sums.
shared vec4 s_a[(TILE_Y + 2 * RADIUS) * TILE_X];
shared vec2 s_b[(TILE_Y + 2 * RADIUS) * TILE_X];

void main() {
  ivec2 group_first = ivec2(gl_WorkGroupID.xy) * ivec2(TILE_X, TILE_Y);
  ivec2 local = ivec2(gl_LocalInvocationID.xy);
  for (int i = local.y * TILE_X + local.x; i < (TILE_Y + 2 * RADIUS) * TILE_X;
       i += TILE_X * TILE_Y) {
    ivec2 at = group_first + ivec2(i % TILE_X, i / TILE_X);
    s_a[i] = imageLoad(u_sums0, at);
    s_b[i] = imageLoad(u_sums1, at).xy;
  }
  barrier();
  g_column = group_first.x + local.x;
  g_first = group_first.y + local.y;
  if (g_column >= u_size.x || g_first >= u_size.y) return;
  Sums acc = ZeroSums();
  for (int i = 0; i <= 2 * RADIUS; ++i) {
    int k = (local.y + i) * TILE_X + local.x;
    Tap(acc, u_weights[i], Sums(s_a[k], s_b[k]));
  }
  FinishOutput(0, acc);
}
#endif
