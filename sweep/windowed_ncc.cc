#include "sweep/windowed_ncc.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/check.h"
#include "sweep/subnormals.h"
#include "sweep/vector_clones.h"

#if MS_HAVE_AVX512_DISPATCH
#include <immintrin.h>
#endif

namespace ms {

// One row of the images behind the six quantities: m, I (C's image minus 0.5) and J (already 0
// where m is). All zeros outside the image.
struct RowInputs {
  const float* __restrict m;
  const float* __restrict i;
  const float* __restrict j;
};

namespace {

constexpr int kLanes = WindowedNcc::kLanes;
constexpr int kQuantities = WindowedNcc::kQuantities;
constexpr double kVarianceFloor = 1e-5;  // as WeightedNcc: float round-off of a flat window

struct FloatGaussian {
  float pr[2], pi[2], tr[2], ti[2], wr[2], wi[2];
  int radius;
};

FloatGaussian ToFloat(const RecursiveGaussian& g) {
  FloatGaussian f;
  for (int k = 0; k < 2; ++k) {
    f.pr[k] = static_cast<float>(g.pole[k].real());
    f.pi[k] = static_cast<float>(g.pole[k].imag());
    f.tr[k] = static_cast<float>(g.tail[k].real());
    f.ti[k] = static_cast<float>(g.tail[k].imag());
    f.wr[k] = static_cast<float>(g.weight[k].real());
    f.wi[k] = static_cast<float>(g.weight[k].imag());
  }
  f.radius = g.radius;
  return f;
}

// Eight floats (the rows of a block), held in registers. The helpers are internal and inlined,
// so the AVX calling convention GCC warns about never crosses a library boundary.
#pragma GCC diagnostic ignored "-Wpsabi"
typedef float Lanes __attribute__((vector_size(32)));
// Sixteen floats: the AVX-512 versions' vectors (two groups of 8 columns side by side, or two
// quantities' 8 rows).
typedef float WideLanes __attribute__((vector_size(64)));
constexpr int kWideLanes = 2 * kLanes;

inline Lanes LoadLanes(const float* p) {
  Lanes v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

inline void StoreLanes(float* p, Lanes v) { __builtin_memcpy(p, &v, sizeof v); }

// The helpers below are inlined into each clone of the vectorised loops that call them, so that
// they take that clone's instruction set (and its fused multiply-adds).
#define MS_ALWAYS_INLINE inline __attribute__((always_inline))

// Loads and stores of one float, 8 or 16.
template <typename V>
MS_ALWAYS_INLINE V Load(const float* p) {
  V v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

template <typename V>
MS_ALWAYS_INLINE void Store(float* p, V v) {
  __builtin_memcpy(p, &v, sizeof v);
}

// A store that bypasses the caches, for pass 1's output: it is read back only by pass 2, after
// the whole image, so caching it only costs a read of each line before it is written.
// p: aligned to the vector's size.
template <typename V>
MS_ALWAYS_INLINE void StoreStreaming(float* p, V v) {
#if MS_HAVE_AVX512_DISPATCH
  if constexpr (sizeof(V) == 64) {
    __builtin_ia32_movntps512(p, reinterpret_cast<__m512>(v));
    return;
  }
  if constexpr (sizeof(V) == 32) {  // SSE's, which every x86-64 has
    typedef float Half __attribute__((vector_size(16)));
    Half halves[2];
    __builtin_memcpy(halves, &v, sizeof v);
    __builtin_ia32_movntps(p, halves[0]);
    __builtin_ia32_movntps(p + 4, halves[1]);
    return;
  }
#endif
  Store(p, v);
}

// The six quantities m, mI, J, mI^2, J^2, IJ at column c of one row.
template <typename V>
MS_ALWAYS_INLINE void Products(const RowInputs& r, size_t c, V out[kQuantities]) {
  const V m = Load<V>(r.m + c), i = Load<V>(r.i + c), j = Load<V>(r.j + c);
  out[0] = m;
  out[1] = m * i;
  out[2] = j;
  out[3] = m * (i * i);  // I^2 taken here rather than stored: one stream less from memory
  out[4] = j * j;
  out[5] = i * j;
}

// Where column c's values of the six quantities lie in a row interleaved by groups of 16 columns
// ([col / 16][quantity][col % 16]): the vertical passes then stream one array instead of six, and
// their many rows never compete for the same cache sets. A group is one 16-float vector or two
// 8-float ones.
constexpr int kGroup = WindowedNcc::kColumnGroup;

MS_ALWAYS_INLINE size_t Grouped(size_t c, int q, int per_column) {
  return (c / kGroup * per_column + q) * kGroup + c % kGroup;
}

// The size of a grouped row of n columns.
size_t GroupedSize(size_t n, int per_column) {
  return (n + kGroup - 1) / kGroup * per_column * kGroup;
}

// The vertical recursions' state, 4 values per quantity: Grouped(c, 4 q + k, 24).
constexpr int kStates = 4 * kQuantities;

// Quantity q's state at column c: the two complex poles' recursions, real and imaginary parts.
template <typename V>
struct PoleStates {
  V r0, i0, r1, i1;
};

template <typename V>
MS_ALWAYS_INLINE PoleStates<V> LoadPoles(const float* state, size_t c, int q) {
  const float* s = state + Grouped(c, 4 * q, kStates);
  return {Load<V>(s), Load<V>(s + kGroup), Load<V>(s + 2 * kGroup), Load<V>(s + 3 * kGroup)};
}

template <typename V>
MS_ALWAYS_INLINE void StorePoles(float* state, size_t c, int q, const PoleStates<V>& a) {
  float* s = state + Grouped(c, 4 * q, kStates);
  Store(s, a.r0);
  Store(s + kGroup, a.i0);
  Store(s + 2 * kGroup, a.r1);
  Store(s + 3 * kGroup, a.i1);
}

// One step of the causal recursion down column c for every quantity (see recursive_gaussian.h):
// s = pole s + x - tail x_tail per pole; out = the output, a grouped row.
template <typename V>
MS_ALWAYS_INLINE void CausalColumns(const FloatGaussian& g, float* __restrict state,
                                    const RowInputs& x, const RowInputs& x_tail,
                                    float* __restrict out, size_t c) {
  V xv[kQuantities], tv[kQuantities];
  Products(x, c, xv);
  Products(x_tail, c, tv);
#pragma GCC unroll 6
  for (int q = 0; q < kQuantities; ++q) {
    const auto [r0, i0, r1, i1] = LoadPoles<V>(state, c, q);
    const V a0r = g.pr[0] * r0 - g.pi[0] * i0 + xv[q] - g.tr[0] * tv[q];
    const V a0i = g.pr[0] * i0 + g.pi[0] * r0 - g.ti[0] * tv[q];
    const V a1r = g.pr[1] * r1 - g.pi[1] * i1 + xv[q] - g.tr[1] * tv[q];
    const V a1i = g.pr[1] * i1 + g.pi[1] * r1 - g.ti[1] * tv[q];
    StorePoles<V>(state, c, q, {a0r, a0i, a1r, a1i});
    StoreStreaming(out + Grouped(c, q, kQuantities),
                   g.wr[0] * a0r - g.wi[0] * a0i + g.wr[1] * a1r - g.wi[1] * a1i);
  }
}

// One step of the anticausal recursion: a = pole (a + x_next) - tail x_tail; out = causal (a
// grouped row) + its output ([quantity], `out_stride` apart).
template <typename V>
MS_ALWAYS_INLINE void AnticausalColumns(const FloatGaussian& g, float* __restrict state,
                                        const RowInputs& x_next, const RowInputs& x_tail,
                                        const float* __restrict causal, float* __restrict out,
                                        size_t out_stride, size_t c) {
  V xv[kQuantities], tv[kQuantities];
  Products(x_next, c, xv);
  Products(x_tail, c, tv);
#pragma GCC unroll 6
  for (int q = 0; q < kQuantities; ++q) {
    const auto [r0, i0, r1, i1] = LoadPoles<V>(state, c, q);
    const V u0 = r0 + xv[q], u1 = r1 + xv[q];
    const V a0r = g.pr[0] * u0 - g.pi[0] * i0 - g.tr[0] * tv[q];
    const V a0i = g.pr[0] * i0 + g.pi[0] * u0 - g.ti[0] * tv[q];
    const V a1r = g.pr[1] * u1 - g.pi[1] * i1 - g.tr[1] * tv[q];
    const V a1i = g.pr[1] * i1 + g.pi[1] * u1 - g.ti[1] * tv[q];
    StorePoles<V>(state, c, q, {a0r, a0i, a1r, a1i});
    Store(out + q * out_stride + c, Load<V>(causal + Grouped(c, q, kQuantities)) + g.wr[0] * a0r -
                                        g.wi[0] * a0i + g.wr[1] * a1r - g.wi[1] * a1i);
  }
}

// Calls step(V(), c) over the columns of a row of n: Wide vectors (Lanes, or WideLanes where
// AVX-512 is), then 8 floats, then single floats; every column gets the same arithmetic
// whichever takes it.
template <typename Wide, typename Step>
MS_ALWAYS_INLINE void ForEachColumnVector(int n, Step&& step) {
  const size_t end = static_cast<size_t>(n);
  constexpr size_t kWide = sizeof(Wide) / sizeof(float);
  size_t c = 0;
  for (; c + kWide <= end; c += kWide) step(Wide(), c);
  for (; c + kLanes <= end; c += kLanes) step(Lanes(), c);
  for (; c < end; ++c) step(float(), c);
}

// The causal step of a whole row: all six quantities at once, so each input row is read once.
template <typename Wide>
MS_ALWAYS_INLINE void CausalRowWith(const FloatGaussian& g, float* __restrict state, RowInputs x,
                                    RowInputs x_tail, float* __restrict out, int n) {
  ForEachColumnVector<Wide>(
      n, [&](auto v, size_t c) __attribute__((always_inline)) {
        CausalColumns<decltype(v)>(g, state, x, x_tail, out, c);
      });
}

// The anticausal step of a whole row, all six quantities at once.
template <typename Wide>
MS_ALWAYS_INLINE void AnticausalRowWith(const FloatGaussian& g, float* __restrict state,
                                        RowInputs x_next, RowInputs x_tail,
                                        const float* __restrict causal, float* __restrict out,
                                        size_t out_stride, int n) {
  ForEachColumnVector<Wide>(
      n, [&](auto v, size_t c) __attribute__((always_inline)) {
        AnticausalColumns<decltype(v)>(g, state, x_next, x_tail, causal, out, out_stride, c);
      });
}

MS_VECTOR_CLONES void CausalRow(const FloatGaussian& g, float* __restrict state, RowInputs x,
                                RowInputs x_tail, float* __restrict out, int n) {
  CausalRowWith<Lanes>(g, state, x, x_tail, out, n);
}

MS_VECTOR_CLONES void AnticausalRow(const FloatGaussian& g, float* __restrict state,
                                    RowInputs x_next, RowInputs x_tail,
                                    const float* __restrict causal, float* __restrict out,
                                    size_t out_stride, int n) {
  AnticausalRowWith<Lanes>(g, state, x_next, x_tail, causal, out, out_stride, n);
}

#if MS_HAVE_AVX512_DISPATCH
MS_AVX512 void CausalRowAvx512(const FloatGaussian& g, float* __restrict state, RowInputs x,
                               RowInputs x_tail, float* __restrict out, int n) {
  CausalRowWith<WideLanes>(g, state, x, x_tail, out, n);
}

MS_AVX512 void AnticausalRowAvx512(const FloatGaussian& g, float* __restrict state,
                                   RowInputs x_next, RowInputs x_tail,
                                   const float* __restrict causal, float* __restrict out,
                                   size_t out_stride, int n) {
  AnticausalRowWith<WideLanes>(g, state, x_next, x_tail, causal, out, out_stride, n);
}
#endif

// A block of 8 rows transposed for the horizontal recursions: [quantity / 2][col][quantity %
// 2][lane], two quantities' 8 rows side by side, so that one 16-float vector holds a pair.
// `pair_plane` = 16 x the image's width.
MS_ALWAYS_INLINE size_t BlockIndex(int q, size_t col, size_t pair_plane) {
  return q / 2 * pair_plane + col * kWideLanes + q % 2 * kLanes;
}

// The horizontal recursions of Q vectors of a block ([col] kWideLanes apart, the Q at `offset`):
// 8 rows of one quantity (V = Lanes) or of a pair (V = WideLanes). Each step's result waits on
// the step before it, so the Q run side by side to keep the multiply-add units busy.
template <typename V, int Q>
MS_ALWAYS_INLINE void HorizontalBlockWith(const FloatGaussian& g, const float* __restrict in,
                                          float* __restrict out, const size_t offset[Q], int n) {
  const float p0r = g.pr[0], p0i = g.pi[0], p1r = g.pr[1], p1i = g.pi[1];
  const float t0r = g.tr[0], t0i = g.ti[0], t1r = g.tr[1], t1i = g.ti[1];
  const float w0r = g.wr[0], w0i = g.wi[0], w1r = g.wr[1], w1i = g.wi[1];
  const int r = g.radius;
  constexpr size_t kStep = kWideLanes;
  V s0r[Q] = {}, s0i[Q] = {}, s1r[Q] = {}, s1i[Q] = {};
  for (int col = 0; col < n; ++col) {
#pragma GCC unroll 4
    for (int q = 0; q < Q; ++q) {
      const float* x_in = in + offset[q];
      const V x = Load<V>(x_in + col * kStep);
      const V t = col > r ? Load<V>(x_in + (col - r - 1) * kStep) : V{};
      const V a0r = p0r * s0r[q] - p0i * s0i[q] + x - t0r * t;
      const V a0i = p0r * s0i[q] + p0i * s0r[q] - t0i * t;
      const V a1r = p1r * s1r[q] - p1i * s1i[q] + x - t1r * t;
      const V a1i = p1r * s1i[q] + p1i * s1r[q] - t1i * t;
      s0r[q] = a0r;
      s0i[q] = a0i;
      s1r[q] = a1r;
      s1i[q] = a1i;
      Store(out + offset[q] + col * kStep, w0r * a0r - w0i * a0i + w1r * a1r - w1i * a1i);
    }
  }
#pragma GCC unroll 4
  for (int q = 0; q < Q; ++q) s0r[q] = s0i[q] = s1r[q] = s1i[q] = V{};
  for (int col = n - 1; col >= 0; --col) {
#pragma GCC unroll 4
    for (int q = 0; q < Q; ++q) {
      const float* x_in = in + offset[q];
      const V x = col + 1 < n ? Load<V>(x_in + (col + 1) * kStep) : V{};
      const V t = col + r + 1 < n ? Load<V>(x_in + (col + r + 1) * kStep) : V{};
      const V u0 = s0r[q] + x, u1 = s1r[q] + x;
      const V a0r = p0r * u0 - p0i * s0i[q] - t0r * t;
      const V a0i = p0r * s0i[q] + p0i * u0 - t0i * t;
      const V a1r = p1r * u1 - p1i * s1i[q] - t1r * t;
      const V a1i = p1r * s1i[q] + p1i * u1 - t1i * t;
      s0r[q] = a0r;
      s0i[q] = a0i;
      s1r[q] = a1r;
      s1i[q] = a1i;
      float* y = out + offset[q] + col * kStep;
      Store(y, Load<V>(y) + w0r * a0r - w0i * a0i + w1r * a1r - w1i * a1i);
    }
  }
}

// The six quantities' horizontal recursions over a block, three at a time: fewer streams leave
// the core's multiply-add units idle, more spill registers.
MS_VECTOR_CLONES void HorizontalBlock(const FloatGaussian& g, const float* __restrict in,
                                      float* __restrict out, size_t pair_plane, int n) {
  for (int first = 0; first < kQuantities; first += 3) {
    const size_t offset[3] = {BlockIndex(first, 0, pair_plane),
                              BlockIndex(first + 1, 0, pair_plane),
                              BlockIndex(first + 2, 0, pair_plane)};
    HorizontalBlockWith<Lanes, 3>(g, in, out, offset, n);
  }
}

#if MS_HAVE_AVX512_DISPATCH
// The same with the three pairs side by side in 16-float vectors.
MS_AVX512 void HorizontalBlockAvx512(const FloatGaussian& g, const float* __restrict in,
                                     float* __restrict out, size_t pair_plane, int n) {
  const size_t offset[3] = {0, pair_plane, 2 * pair_plane};
  HorizontalBlockWith<WideLanes, 3>(g, in, out, offset, n);
}
#endif

// Lane-wise comparison results (all bits set where true), and shuffle indices.
typedef int32_t LaneMask __attribute__((vector_size(32)));

// An 8 x 8 tile transposed in registers: r[l][k] -> r[k][l] (unpack, shuffle, swap halves: three
// stages of shuffles).
MS_ALWAYS_INLINE void Transpose8x8(Lanes r[kLanes]) {
  using Mask = LaneMask;
  const Mask lo = {0, 8, 1, 9, 4, 12, 5, 13}, hi = {2, 10, 3, 11, 6, 14, 7, 15};
  const Mask lo2 = {0, 1, 8, 9, 4, 5, 12, 13}, hi2 = {2, 3, 10, 11, 6, 7, 14, 15};
  const Mask lo4 = {0, 1, 2, 3, 8, 9, 10, 11}, hi4 = {4, 5, 6, 7, 12, 13, 14, 15};
  Lanes u[kLanes], v[kLanes];
  for (int p = 0; p < kLanes; p += 2) {
    u[p] = __builtin_shuffle(r[p], r[p + 1], lo);
    u[p + 1] = __builtin_shuffle(r[p], r[p + 1], hi);
  }
  for (int p = 0; p < kLanes; p += 4) {
    v[p] = __builtin_shuffle(u[p], u[p + 2], lo2);
    v[p + 1] = __builtin_shuffle(u[p], u[p + 2], hi2);
    v[p + 2] = __builtin_shuffle(u[p + 1], u[p + 3], lo2);
    v[p + 3] = __builtin_shuffle(u[p + 1], u[p + 3], hi2);
  }
  for (int k = 0; k < 4; ++k) {  // v[k]: columns k and k + 4 of rows 0-3, v[k + 4] of rows 4-7
    r[k] = __builtin_shuffle(v[k], v[k + 4], lo4);
    r[k + 4] = __builtin_shuffle(v[k], v[k + 4], hi4);
  }
}

// WeightedNcc's formula for the 8 rows of one column of a block, from the six sums at `s`
// (BlockIndex(0, col)): the NCC, and where it is defined (all bits set) unless the pixel is
// masked out.
struct ColumnNcc {
  Lanes value;
  LaneMask ok;
};

MS_ALWAYS_INLINE ColumnNcc NccOfColumn(const float* __restrict s, size_t pair_plane,
                                       float min_variance, float min_weight) {
  const float floor = static_cast<float>(kVarianceFloor);
  const auto sum = [&](int q) { return LoadLanes(s + BlockIndex(q, 0, pair_plane)); };
  const Lanes w = sum(0);
  const Lanes inv_w = 1.0f / w;
  const Lanes mean_i = sum(1) * inv_w;
  const Lanes mean_j = sum(2) * inv_w;
  const Lanes ii = sum(3) * inv_w;
  const Lanes jj = sum(4) * inv_w;
  Lanes ij = sum(5) * inv_w;
  // Rounded before ij - mean_i mean_j, as the kernel has always done: which product a fused
  // multiply-add takes moves NCCs by an ulp, and with them tile winners and whole runs.
  __asm__("" : "+m"(ij));
  const Lanes var_i = ii - mean_i * mean_i, var_j = jj - mean_j * mean_j;
  const LaneMask ok = (w >= min_weight) & (var_i > min_variance) & (var_i > floor * ii) &
                      (var_j > min_variance) & (var_j > floor * jj);
  Lanes product = var_i * var_j;
  product = product > 0 ? product : Lanes{};
  Lanes root;  // one vector square root (this file is compiled without errno from sqrt)
  for (int l = 0; l < kLanes; ++l) root[l] = __builtin_sqrtf(product[l]);
  Lanes value = (ij - mean_i * mean_j) / root;
  value = value > 1.0f ? Lanes{} + 1.0f : value;
  value = value < -1.0f ? Lanes{} - 1.0f : value;
  return {value, ok};
}

// NCC of up to 8 rows of a block from their six sums (BlockIndex): WeightedNcc's formula, 8 rows
// at a time; 8 columns at a time are turned back into rows ([lane][col]) to be masked and stored
// (rows `stride` apart). Returns the number of defined pixels.
MS_VECTOR_CLONES int64_t NccBlock(const float* __restrict sums, size_t pair_plane,
                                  const float* __restrict mask, float* __restrict ncc, int width,
                                  size_t stride, int rows, double min_texture_variance,
                                  double min_window_weight) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float min_variance = static_cast<float>(min_texture_variance);
  const float min_weight = static_cast<float>(min_window_weight);
  int64_t defined = 0;
  int col = 0;
  for (; col + kLanes <= width; col += kLanes) {
    Lanes value[kLanes], ok[kLanes];  // [column][row], then [row][column]
    for (int k = 0; k < kLanes; ++k) {
      const ColumnNcc c = NccOfColumn(sums + static_cast<size_t>(col + k) * kWideLanes, pair_plane,
                                      min_variance, min_weight);
      value[k] = c.value;
      ok[k] = __builtin_bit_cast(Lanes, c.ok);
    }
    Transpose8x8(value);
    Transpose8x8(ok);
    for (int lane = 0; lane < rows; ++lane) {
      const size_t index = static_cast<size_t>(lane) * stride + col;
      const LaneMask valid = (LoadLanes(mask + index) > 0) & __builtin_bit_cast(LaneMask, ok[lane]);
      StoreLanes(ncc + index, valid ? value[lane] : Lanes{} + nan);
      for (int k = 0; k < kLanes; ++k) defined += valid[k] != 0;
    }
  }
  for (; col < width; ++col) {
    const ColumnNcc c = NccOfColumn(sums + static_cast<size_t>(col) * kWideLanes, pair_plane,
                                    min_variance, min_weight);
    for (int lane = 0; lane < rows; ++lane) {
      const size_t index = static_cast<size_t>(lane) * stride + col;
      const bool valid = mask[index] > 0 && c.ok[lane];
      ncc[index] = valid ? c.value[lane] : nan;
      defined += valid;
    }
  }
  return defined;
}

// Eight rows of one quantity ([lane][col], `stride` apart) into its place in a block ([col][lane],
// columns kWideLanes apart), 8 x 8 tiles at a time.
MS_VECTOR_CLONES void RowsToBlock(const float* __restrict rows, size_t stride,
                                  float* __restrict block, int n) {
  int c = 0;
  for (; c + kLanes <= n; c += kLanes) {
    Lanes r[kLanes];
    for (int l = 0; l < kLanes; ++l) r[l] = LoadLanes(rows + l * stride + c);
    Transpose8x8(r);
    for (int k = 0; k < kLanes; ++k) StoreLanes(block + (c + k) * kWideLanes, r[k]);
  }
  for (; c < n; ++c) {
    for (int l = 0; l < kLanes; ++l) block[c * kWideLanes + l] = rows[l * stride + c];
  }
}

}  // namespace

bool WindowedNcc::MachineHasAvx512() {
#if MS_HAVE_AVX512_DISPATCH
  static const bool has = __builtin_cpu_supports("x86-64-v4");
  return has;
#else
  return false;
#endif
}

WindowedNcc::WindowedNcc(int width, int height, double sigma_px, double min_texture_variance,
                         double min_window_weight, Vectors vectors)
    : width_(width),
      height_(height),
      gaussian_(RecursiveGaussian::Make(sigma_px)),
      min_texture_variance_(min_texture_variance),
      min_window_weight_(min_window_weight),
      avx512_(vectors == Vectors::kWidest && MachineHasAvx512()) {
  MS_CHECK(width > 0 && height > 0) << "bad NCC image size";
  const size_t n = static_cast<size_t>(width) * height;
  i_.resize(n);
  causal_.resize(GroupedSize(width, kQuantities) * height);
  MS_CHECK(reinterpret_cast<uintptr_t>(causal_.data()) % 64 == 0) << "NCC buffer not aligned";
  state_.resize(GroupedSize(width, kStates));
  zeros_.assign(width, 0.0f);
  block_.resize(static_cast<size_t>(kQuantities) * width * kLanes);
  rows_.assign(RowsOffset(kQuantities, 0), 0.0f);
  sums_.resize(block_.size());
}

void WindowedNcc::SetCamera(const cv::Mat& image) {
  MS_CHECK(image.type() == CV_32F && image.cols == width_ && image.rows == height_)
      << "NCC camera image of the wrong size or type";
  for (int row = 0; row < height_; ++row) {
    const float* in = image.ptr<float>(row);
    float* i = i_.data() + static_cast<size_t>(row) * width_;
    for (int c = 0; c < width_; ++c) i[c] = in[c] - 0.5f;
  }
}

RowInputs WindowedNcc::Inputs(int row) const {
  if (row < 0 || row >= height_) {
    const float* zeros = zeros_.data() + window_.first_col;
    return {zeros, zeros, zeros};
  }
  const size_t offset = static_cast<size_t>(row) * width_ + window_.first_col;
  return {mask_ + offset, i_.data() + offset, J_ + offset};
}

// The rectangle around the valid pixels, widened to whole blocks of 8 rows, to a whole group of
// 16 columns on the left and 8 on the right (or the image's edge), so that every value computed
// in it gets the same arithmetic as over the whole image.
WindowedNcc::Window WindowedNcc::ValidWindow() const {
  const size_t w = width_;
  const auto row_of = [&](int row) { return mask_ + row * w; };
  const auto empty_row = [&](int row) {
    return std::all_of(row_of(row), row_of(row) + w, [](float m) { return m == 0; });
  };
  int first_row = 0, last_row = height_ - 1;
  while (first_row < height_ && empty_row(first_row)) ++first_row;
  if (first_row == height_) return {};
  while (empty_row(last_row)) --last_row;
  // Only the columns outside the rectangle so far need a look.
  int first_col = width_, last_col = -1;
  for (int row = first_row; row <= last_row; ++row) {
    const float* m = row_of(row);
    for (int c = 0; c < first_col; ++c) {
      if (m[c] != 0) first_col = c;
    }
    for (int c = width_ - 1; c > last_col; --c) {
      if (m[c] != 0) last_col = c;
    }
  }
  Window window;
  window.first_row = first_row / kLanes * kLanes;
  window.last_row = std::min(height_ - 1, last_row / kLanes * kLanes + kLanes - 1);
  window.first_col = first_col / kGroup * kGroup;
  window.cols =
      std::min(width_ - 1, last_col / kLanes * kLanes + kLanes - 1) - window.first_col + 1;
  return window;
}

int64_t WindowedNcc::Run(const float* J, const float* mask, float* ncc) {
  const ScopedFlushSubnormals flush;
  J_ = J;
  mask_ = mask;
  window_ = ValidWindow();
  const size_t w = width_;
  // Outside the window every pixel is masked out.
  for (int row = 0; row < height_; ++row) {
    float* out = ncc + row * w;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    if (row < window_.first_row || row > window_.last_row) {
      std::fill(out, out + w, nan);
    } else {
      std::fill(out, out + window_.first_col, nan);
      std::fill(out + window_.first_col + window_.cols, out + w, nan);
    }
  }
  if (window_.cols == 0) return 0;
  // Every product is 0 outside the window (J and the mask are), so the recursions enter it
  // with the state they would have had over the whole image: 0.
  const FloatGaussian g = ToFloat(gaussian_);
  const int r = gaussian_.radius, n = window_.cols;
  float* state = state_.data() + Grouped(window_.first_col, 0, kStates);
  const size_t row_size = GroupedSize(w, kQuantities);
  float* causal = causal_.data() + Grouped(window_.first_col, 0, kQuantities);

  // Pass 1: vertical causal, top to bottom.
  std::fill(state_.begin(), state_.end(), 0.0f);
  auto causal_row = CausalRow;
  auto anticausal_row = AnticausalRow;
#if MS_HAVE_AVX512_DISPATCH
  if (avx512_) {
    causal_row = CausalRowAvx512;
    anticausal_row = AnticausalRowAvx512;
  }
#endif
  for (int row = window_.first_row; row <= window_.last_row; ++row) {
    causal_row(g, state, Inputs(row), Inputs(row - r - 1), causal + row * row_size, n);
  }

  // Pass 2: vertical anticausal, bottom to top; horizontal and NCC every 8 rows.
  std::fill(state_.begin(), state_.end(), 0.0f);
  int64_t defined = 0;
  for (int row = window_.last_row; row >= window_.first_row; --row) {
    const int lane = row % kLanes;
    anticausal_row(g, state, Inputs(row + 1), Inputs(row + r + 1), causal + row * row_size,
                   rows_.data() + RowsOffset(0, lane) + window_.first_col, RowsOffset(1, 0), n);
    if (lane == 0) FinishBlock(row, ncc, &defined);
  }
  return defined;
}

void WindowedNcc::FinishBlock(int first_row, float* ncc, int64_t* defined) {
  const int w = width_, n = window_.cols;
  const int rows = std::min(kLanes, height_ - first_row);
  const size_t pair_plane = static_cast<size_t>(w) * kWideLanes;
  for (int q = 0; q < kQuantities; ++q) {
    RowsToBlock(rows_.data() + RowsOffset(q, 0) + window_.first_col, w,
                block_.data() + BlockIndex(q, 0, pair_plane), n);
  }
  auto horizontal = HorizontalBlock;
#if MS_HAVE_AVX512_DISPATCH
  if (avx512_) horizontal = HorizontalBlockAvx512;
#endif
  horizontal(ToFloat(gaussian_), block_.data(), sums_.data(), pair_plane, n);
  const size_t offset = static_cast<size_t>(first_row) * w + window_.first_col;
  *defined += NccBlock(sums_.data(), pair_plane, mask_ + offset, ncc + offset, n, w, rows,
                       min_texture_variance_, min_window_weight_);
}

}  // namespace ms
