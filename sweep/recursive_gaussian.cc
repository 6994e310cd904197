#include "sweep/recursive_gaussian.h"

#include <cmath>

#include "base/check.h"

namespace ms {
namespace {

// Deriche's fit of exp(-x^2 / 2 sigma^2), x >= 0, in units of sigma:
//   sum_k (a_k cos(w_k x) + b_k sin(w_k x)) exp(-l_k x) = sum_k Re((a_k - i b_k) e^{(-l_k + i w_k)
//   x}).
constexpr double kA[2] = {1.68, -0.6803};
constexpr double kB[2] = {3.735, -0.2598};
constexpr double kOmega[2] = {0.6318, 1.997};
constexpr double kLambda[2] = {1.783, 1.723};

}  // namespace

RecursiveGaussian RecursiveGaussian::Make(double sigma_px) {
  MS_CHECK(sigma_px > 0) << "sigma must be positive";
  RecursiveGaussian g;
  g.radius = static_cast<int>(std::ceil(3 * sigma_px));
  for (int k = 0; k < 2; ++k) {
    g.pole[k] = std::exp(std::complex<double>(-kLambda[k], kOmega[k]) / sigma_px);
    g.tail[k] = std::pow(g.pole[k], g.radius + 1);
    g.weight[k] = {kA[k], -kB[k]};
  }
  double sum = 0;
  for (int m = -g.radius; m <= g.radius; ++m) sum += g.Tap(m);
  for (auto& w : g.weight) w /= sum;
  return g;
}

double RecursiveGaussian::Tap(int m) const {
  m = std::abs(m);
  if (m > radius) return 0;
  double h = 0;
  for (int k = 0; k < 2; ++k) h += (weight[k] * std::pow(pole[k], m)).real();
  return h;
}

std::vector<double> RecursiveGaussianFilter(const RecursiveGaussian& g,
                                            const std::vector<double>& x) {
  const int n = static_cast<int>(x.size());
  const auto at = [&](int i) { return i >= 0 && i < n ? x[i] : 0.0; };
  std::vector<double> y(n, 0.0);
  for (int k = 0; k < 2; ++k) {
    std::complex<double> s = 0;
    for (int i = 0; i < n; ++i) {
      s = g.pole[k] * s + at(i) - g.tail[k] * at(i - g.radius - 1);
      y[i] += (g.weight[k] * s).real();
    }
    std::complex<double> a = 0;
    for (int i = n - 1; i >= 0; --i) {
      a = g.pole[k] * (a + at(i + 1)) - g.tail[k] * at(i + g.radius + 1);
      y[i] += (g.weight[k] * a).real();
    }
  }
  return y;
}

}  // namespace ms
