// The tap loop shared by the two separable passes of the NCC's Gaussian blur (sweep_blur_rows,
// sweep_blur_ncc). An invocation owns BLOCK consecutive outputs of one image line; output o sums
// samples o .. o + 2 RADIUS of the line (the input lines are padded with RADIUS zeros before
// pixel 0 and RADIUS + BLOCK after the last one: zero outside the image, as the reference).
// The including pass defines Sums (six channels: a = (W, S_I, S_J, S_II), b = (S_JJ, S_IJ)),
// BeginLine() (false: nothing to do), LoadSample(i) and FinishOutput(o, sums).
//
// With UNROLLED the kernel (worker/glsl_sweep.cc) replaces the marker below with the loop fully
// unrolled: every sample is loaded once and kept in registers for all the outputs that use it,
// which is what a CPU rasterizer (llvmpipe) needs; GPUs take the loop (texture caches do the
// reuse).
uniform float u_weights[2 * RADIUS + 1];  // GaussianWindow(sigma), normalised to sum 1

// fma(): one rounding per channel and tap (the sums differ from OpenCV's only in their order).
void Tap(inout Sums acc, float w, Sums s) {
  acc.a = fma(vec4(w), s.a, acc.a);
  acc.b = fma(vec2(w), s.b, acc.b);
}

Sums ZeroSums() { return Sums(vec4(0.0), vec2(0.0)); }

#if !TILED  // else the including pass stages its samples in shared memory
void main() {
  if (!BeginLine()) return;
#if UNROLLED
  // @MS_UNROLLED_TAPS@
#else
  for (int o = 0; o < BLOCK; ++o) {
    Sums acc = ZeroSums();
    for (int i = 0; i <= 2 * RADIUS; ++i) Tap(acc, u_weights[i], LoadSample(o + i));
    FinishOutput(o, acc);
  }
#endif
}
#endif
