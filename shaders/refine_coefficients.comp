#version 430 core
// Photometric gradient, second pass: each defined pixel's 1 - ZNCC and the coefficients of
// dZNCC_p/dJ(q) (photometric_gradient_fast.cc): a = 1 / (S_m sqrt(var_I var_J)), a mu_I,
// b = ZNCC / (S_m var_J), b mu_J; zero, and energy -1, where ZNCC is undefined. Statistics in
// double, as the CPU kernels take them from float sums.
layout(local_size_x = 16, local_size_y = 8) in;

layout(binding = 0, rgba32f) readonly uniform image2D u_window0;  // m, ...
layout(binding = 1, rgba32f) readonly uniform image2D u_sums0;    // G*m, G*mI, G*mJ, G*mI^2
layout(binding = 2, rgba32f) readonly uniform image2D u_sums1;    // G*mJ^2, G*mIJ, -, -
layout(binding = 3, rgba32f) writeonly uniform image2D o_coefficients;
layout(binding = 4, r32f) writeonly uniform image2D o_energy;

uniform ivec2 u_size;
uniform float u_min_variance;

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= u_size.x || p.y >= u_size.y) return;
  vec4 s0 = imageLoad(u_sums0, p);
  vec4 s1 = imageLoad(u_sums1, p);
  double weight = double(s0.x);
  if (imageLoad(u_window0, p).x == 0.0 || weight < 0.5) {  // half the window at least
    imageStore(o_coefficients, p, vec4(0.0));
    imageStore(o_energy, p, vec4(-1.0));
    return;
  }
  double mu_i = double(s0.y) / weight, mu_j = double(s0.z) / weight;
  double var_i = double(s0.w) / weight - mu_i * mu_i;
  double var_j = double(s1.x) / weight - mu_j * mu_j;
  if (var_i < double(u_min_variance) || var_j < double(u_min_variance)) {
    imageStore(o_coefficients, p, vec4(0.0));
    imageStore(o_energy, p, vec4(-1.0));
    return;
  }
  double cov = double(s1.y) / weight - mu_i * mu_j;
  double root = sqrt(var_i * var_j);
  double ncc = cov / root;
  imageStore(o_coefficients, p, vec4(1.0 / (weight * root), mu_i / (weight * root),
                                     ncc / (weight * var_j), ncc * mu_j / (weight * var_j)));
  imageStore(o_energy, p, vec4(float(1.0 - ncc)));
}
