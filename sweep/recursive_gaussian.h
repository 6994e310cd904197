// Deriche's recursive approximation of the Gaussian (R. Deriche, "Recursively implementing the
// Gaussian and its derivatives", INRIA RR-1893, 1993), truncated to the reference window's
// support so that it approximates GaussianWindow(sigma) (sweep/sweep_kernel.h) in O(1) per
// sample whatever sigma. The fast CPU kernel's NCC window (sweep/windowed_ncc.h).
//
// The taps are h(m) = sum_k Re(weight_k pole_k^|m|) for |m| <= radius (2 complex poles: a 4th
// order filter), normalised so that they sum to 1. Filtering runs two first-order complex
// recursions per direction; the truncation subtracts pole^(radius+1) times the sample leaving
// the window:
//   causal      s[n] = pole s[n-1] + x[n] - tail x[n-radius-1]   (taps m = 0..radius)
//   anticausal  a[n] = pole (a[n+1] + x[n+1]) - tail x[n+radius+1]   (m = 1..radius)
//   y[n] = sum_k Re(weight_k (s_k[n] + a_k[n])), zero outside the signal as BORDER_CONSTANT.
// Against the exact truncated Gaussian its taps deviate by at most 6e-4 of the peak tap (sum of
// absolute deviations < 3e-4) for sigma in [0.5, 24]; RecursiveGaussianTest measures it.
#pragma once

#include <array>
#include <complex>
#include <vector>

namespace ms {

struct RecursiveGaussian {
  int radius = 0;                                          // ceil(3 sigma), as GaussianWindow
  std::array<std::complex<double>, 2> pole, tail, weight;  // tail = pole^(radius + 1)

  static RecursiveGaussian Make(double sigma_px);
  // h(m): the tap at offset m (0 beyond the radius).
  double Tap(int m) const;
};

// y = h * x on one signal with zeros outside it, by the recursions above (double precision; the
// kernel's vectorised passes do the same in float). For tests.
std::vector<double> RecursiveGaussianFilter(const RecursiveGaussian& g,
                                            const std::vector<double>& x);

}  // namespace ms
