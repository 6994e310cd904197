// The multiply-add rate of one core: the ceiling the CPU sweep kernel's NCC is measured against
// (docs/design/performance.md, "What 100 M hypotheses/s per core would take"). Twelve independent
// chains of vector multiply-adds (more than the latency times the pipes), 8 floats per
// instruction (AVX2) and, where the processor has it, 16 (AVX-512, as the kernel's passes use);
// one thread, best of three runs.
//
//   multiply_add_peak_bench
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "sweep/vector_clones.h"

namespace {

#if MS_HAVE_AVX2_DISPATCH

constexpr int kChains = 12;
constexpr long kSteps = 100'000'000;

template <typename V>
__attribute__((always_inline)) inline double Run() {
  constexpr int kFloats = sizeof(V) / sizeof(float);
  // Twelve named chains, not an array: an array here stays in memory, and its stores and loads
  // would be what is timed.
  V a0 = V{} + 1.000f, a1 = V{} + 1.001f, a2 = V{} + 1.002f, a3 = V{} + 1.003f;
  V a4 = V{} + 1.004f, a5 = V{} + 1.005f, a6 = V{} + 1.006f, a7 = V{} + 1.007f;
  V a8 = V{} + 1.008f, a9 = V{} + 1.009f, a10 = V{} + 1.010f, a11 = V{} + 1.011f;
  const V scale = V{} + 0.999999f, shift = V{} + 1e-7f;
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < kSteps; ++i) {
    a0 = a0 * scale + shift, a1 = a1 * scale + shift, a2 = a2 * scale + shift;
    a3 = a3 * scale + shift, a4 = a4 * scale + shift, a5 = a5 * scale + shift;
    a6 = a6 * scale + shift, a7 = a7 * scale + shift, a8 = a8 * scale + shift;
    a9 = a9 * scale + shift, a10 = a10 * scale + shift, a11 = a11 * scale + shift;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const V all = a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7 + a8 + a9 + a10 + a11;
  float sum = 0;
  for (int l = 0; l < kFloats; ++l) sum += all[l];
  if (!(sum > 0)) std::printf("?");  // uses the result
  return static_cast<double>(kSteps) * kChains * kFloats / seconds;
}

typedef float Avx2 __attribute__((vector_size(32)));
typedef float Avx512 __attribute__((vector_size(64)));

__attribute__((target("avx2,fma"))) double RunAvx2() { return Run<Avx2>(); }
#if MS_HAVE_AVX512_DISPATCH
MS_AVX512 double RunAvx512() { return Run<Avx512>(); }
#endif

template <typename F>
double Best(F run) {
  double best = 0;
  for (int r = 0; r < 3; ++r) best = std::max(best, run());
  return best;
}

#endif  // MS_HAVE_AVX2_DISPATCH

}  // namespace

// The same dispatch as the sweep kernel's (sweep/vector_clones.h): AVX2 on x86-64 with GCC or
// clang, AVX-512 with GCC only; elsewhere there is nothing this benchmark can measure.
int main() {
#if MS_HAVE_AVX2_DISPATCH
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) {
    std::printf("this processor has no AVX2 with FMA: nothing to measure\n");
    return 0;
  }
  std::printf("multiply-adds per second, one core, 8-float vectors (AVX2): %.1f G\n",
              Best(RunAvx2) / 1e9);
#if MS_HAVE_AVX512_DISPATCH
  if (__builtin_cpu_supports("x86-64-v4")) {
    std::printf("multiply-adds per second, one core, 16-float vectors (AVX-512): %.1f G\n",
                Best(RunAvx512) / 1e9);
  }
#endif
#else
  std::printf("built without x86-64 vector dispatch (sweep/vector_clones.h): nothing to measure\n");
#endif
  return 0;
}
