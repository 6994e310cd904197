#include "sweep/span_raster.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "base/check.h"
#include "sweep/raster_rules.h"
#include "sweep/vector_clones.h"

#if MS_HAVE_AVX2_DISPATCH
#include <immintrin.h>
#endif

namespace ms {
using raster::Edge;
using raster::Point2;

namespace {

// Nearest-wins fill of one span: 1/z = inv_z0 + col * inv_z_dx, four pixels at a time; the last
// four again where the span does not end on a multiple (a pixel filled twice is filled as once:
// the second time its value is not nearer than itself), one at a time below four. Written out with
// vectors, a blend and plain stores: left to the vectoriser, the conditional update became masked
// stores (vmaskmovps), which AMD processors execute slowly, and a mesh's spans are short (about
// 10 pixels on fountain-P11's later meshes at full size). The same operations per pixel as the
// plain loop, so the same values. The vectoriser is kept off the function (no-tree-vectorize), or
// it would turn the loop of short spans into masked stores again.
typedef double Doubles4 __attribute__((vector_size(32)));
typedef float Floats4 __attribute__((vector_size(16)));
typedef int32_t Ints4 __attribute__((vector_size(16)));

MS_VECTOR_CLONES __attribute__((optimize("no-tree-vectorize"))) void FillSpan(
    float* __restrict inv_z, int32_t* __restrict faces, int begin, int end, double inv_z0,
    double inv_z_dx, int32_t face) {
  const Doubles4 steps = {0, 1, 2, 3};
  const Ints4 faces4 = Ints4{} + face;
  if (end - begin < 4) {
    for (int col = begin; col < end; ++col) {
      const float value = static_cast<float>(inv_z0 + col * inv_z_dx);
      const bool nearer = value > inv_z[col];
      inv_z[col] = nearer ? value : inv_z[col];
      if (faces != nullptr) faces[col] = nearer ? face : faces[col];
    }
    return;
  }
  for (int next = begin; next < end; next += 4) {
    const int col = std::min(next, end - 4);
    const Doubles4 cols = steps + static_cast<double>(col);
    const Floats4 value = __builtin_convertvector(inv_z0 + cols * inv_z_dx, Floats4);
    Floats4 old;
    __builtin_memcpy(&old, inv_z + col, sizeof old);
    const Ints4 nearer = value > old;
    const Floats4 kept = nearer ? value : old;
    __builtin_memcpy(inv_z + col, &kept, sizeof kept);
    if (faces != nullptr) {
      Ints4 old_faces;
      __builtin_memcpy(&old_faces, faces + col, sizeof old_faces);
      const Ints4 kept_faces = nearer ? faces4 : old_faces;
      __builtin_memcpy(faces + col, &kept_faces, sizeof kept_faces);
    }
  }
}

}  // namespace

SpanRasterizer::SpanRasterizer(const View& view, double near, bool keep_face)
    : keep_face_(keep_face) {
  SetView(view, near);
  Clear();
}

void SpanRasterizer::SetView(const View& view, double near) {
  R_ = view.R;
  t_ = view.t;
  fx_ = view.intrinsics.fx;
  fy_ = view.intrinsics.fy;
  cx_ = view.intrinsics.cx;
  cy_ = view.intrinsics.cy;
  near_ = near;
  width_ = view.intrinsics.width;
  height_ = view.intrinsics.height;
  MS_CHECK(width_ > 0 && height_ > 0 && near_ > 0) << "bad raster target";
  const int bytes_per_row = width_ * (keep_face_ ? 8 : 4);
  band_rows_ = std::clamp((256 << 10) / bytes_per_row, 4, 256);
}

void SpanRasterizer::Clear() {
  const size_t n = static_cast<size_t>(width_) * height_;
  inv_z_.assign(n, 0.0f);
  if (keep_face_) face_.assign(n, -1);
}

void SpanRasterizer::DrawSoup(const std::vector<std::array<Eigen::Vector3d, 3>>& soup) {
  // Each band is cleared just before it is filled, while its rows are in the cache.
  const size_t pixels = static_cast<size_t>(width_) * height_;
  inv_z_.resize(pixels);
  if (keep_face_) face_.resize(pixels);
  projected_.clear();
  for (size_t f = 0; f < soup.size(); ++f) {
    const std::array<Eigen::Vector3d, 3> in = {R_ * soup[f][0] + t_, R_ * soup[f][1] + t_,
                                               R_ * soup[f][2] + t_};
    const auto face = static_cast<int32_t>(f);
    if (in[0].z() >= near_ && in[1].z() >= near_ && in[2].z() >= near_) {
      Project(in[0], in[1], in[2], face);
      continue;
    }
    // Sutherland-Hodgman against z >= near, as SoftwareRasterizer: a fan of at most 2.
    std::array<Eigen::Vector3d, 4> out;
    int n = 0;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d& p = in[i];
      const Eigen::Vector3d& q = in[(i + 1) % 3];
      const bool p_in = p.z() >= near_, q_in = q.z() >= near_;
      if (p_in) out[n++] = p;
      if (p_in != q_in) {
        const double s = (near_ - p.z()) / (q.z() - p.z());
        out[n] = p + s * (q - p);
        out[n++].z() = near_;
      }
    }
    for (int i = 1; i + 1 < n; ++i) Project(out[0], out[i], out[i + 1], face);
  }

  // Each band's triangles in drawing order (a counting sort by band).
  const int bands = (height_ + band_rows_ - 1) / band_rows_;
  band_start_.assign(bands + 1, 0);
  for (const Projected& t : projected_) {
    for (int b = t.row_lo / band_rows_; b <= t.row_hi / band_rows_; ++b) ++band_start_[b + 1];
  }
  for (int b = 0; b < bands; ++b) band_start_[b + 1] += band_start_[b];
  band_triangles_.resize(band_start_[bands]);
  std::vector<uint32_t> next(band_start_.begin(), band_start_.end() - 1);
  for (size_t i = 0; i < projected_.size(); ++i) {
    const Projected& t = projected_[i];
    for (int b = t.row_lo / band_rows_; b <= t.row_hi / band_rows_; ++b) {
      band_triangles_[next[b]++] = static_cast<uint32_t>(i);
    }
  }
  for (int b = 0; b < bands; ++b) {
    const int first = b * band_rows_, last = std::min(height_, first + band_rows_) - 1;
    const size_t band_begin = static_cast<size_t>(first) * width_;
    const size_t band_end = static_cast<size_t>(last + 1) * width_;
    std::fill(inv_z_.begin() + band_begin, inv_z_.begin() + band_end, 0.0f);
    if (keep_face_) std::fill(face_.begin() + band_begin, face_.begin() + band_end, -1);
    for (uint32_t k = band_start_[b]; k < band_start_[b + 1]; ++k) {
      const Projected& t = projected_[band_triangles_[k]];
      FillRows(t, std::max(first, t.row_lo), std::min(last, t.row_hi));
    }
  }
}

void SpanRasterizer::Project(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c, int32_t face) {
  std::array<Point2, 3> p;
  std::array<double, 3> inv_z;
  const std::array<const Eigen::Vector3d*, 3> v = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    inv_z[i] = 1.0 / v[i]->z();
    p[i] = {fx_ * v[i]->x() * inv_z[i] + cx_, fy_ * v[i]->y() * inv_z[i] + cy_};
    if (!std::isfinite(p[i].x) || !std::isfinite(p[i].y)) return;
  }
  const double area = Edge(p[0], p[1], p[2]);
  if (area == 0 || !std::isfinite(area)) return;
  if (area < 0) {  // orient positively; no culling
    std::swap(p[1], p[2]);
    std::swap(inv_z[1], inv_z[2]);
  }
  const double min_x = std::min({p[0].x, p[1].x, p[2].x});
  const double max_x = std::max({p[0].x, p[1].x, p[2].x});
  const double min_y = std::min({p[0].y, p[1].y, p[2].y});
  const double max_y = std::max({p[0].y, p[1].y, p[2].y});
  Projected t;
  t.col_lo = static_cast<int>(std::max(0.0, std::ceil(min_x - 0.5)));
  t.col_hi = static_cast<int>(std::min(width_ - 1.0, std::floor(max_x - 0.5)));
  t.row_lo = static_cast<int>(std::max(0.0, std::ceil(min_y - 0.5)));
  t.row_hi = static_cast<int>(std::min(height_ - 1.0, std::floor(max_y - 0.5)));
  if (t.col_lo > t.col_hi || t.row_lo > t.row_hi) return;

  // 1/z is affine in the image: inv_z(x, y) = gx x + gy y + g0 (screen barycentrics).
  const double twice_area = std::abs(area);
  const auto coverage = [&](double x, double y) {
    const Point2 centre{x, y};
    return std::array<double, 3>{Edge(p[1], p[2], centre), Edge(p[2], p[0], centre),
                                 Edge(p[0], p[1], centre)};
  };
  const std::array<double, 3> w00 = coverage(0, 0), w10 = coverage(1, 0), w01 = coverage(0, 1);
  double g0 = 0, gx = 0, gy = 0;
  for (int i = 0; i < 3; ++i) {
    g0 += w00[i] * inv_z[i];
    gx += (w10[i] - w00[i]) * inv_z[i];
    gy += (w01[i] - w00[i]) * inv_z[i];
  }
  t.g0 = g0 / twice_area;
  t.gx = gx / twice_area;
  t.gy = gy / twice_area;
  t.p = p;
  t.face = face;
  projected_.push_back(t);
}

namespace {

// One edge of a set-up triangle, for finding where its test changes along a row. The exact test
// is raster::Edge and raster::Covers with what does not change along the edge (which end comes
// first, the fill rule) taken out of the loop: the same operations on the same values, so the
// same pixels.
class RowEdge {
 public:
  RowEdge(const Point2& s, const Point2& q)
      : negate_(raster::Before(q, s)),
        top_left_(raster::TopLeft(s, q)),
        first_(negate_ ? q : s),
        ex_((negate_ ? s : q).x - first_.x),
        ey_((negate_ ? s : q).y - first_.y),
        dy_(q.y - s.y),
        x0_(s.x),
        y0_(s.y),
        dx_per_dy_(dy_ == 0 ? 0 : (q.x - s.x) / dy_) {}

  // The interior lies where d(edge)/dx = -dy is positive: right of the crossing for dy < 0
  // (the row's covered columns start here), left for dy > 0 (they end here), the whole row or
  // none of it for dy = 0.
  double dy() const { return dy_; }

  // raster::Covers(raster::Edge(s, q, {col + 0.5, y})), with along = AlongRow(y).
  double AlongRow(double y) const { return ex_ * (y - first_.y); }
  bool Passes(double along, int col) const {
    const double w = along - ey_ * ((col + 0.5) - first_.x);
    const bool inside = negate_ ? w < 0 : w > 0;
    return inside || (w == 0 && top_left_);
  }

  // The first column in [lo, hi] that passes (dy < 0), hi + 1 if none; or the last one that
  // passes (dy > 0), lo - 1 if none. The guess is the column next to the crossing: two tests
  // (it and the column on the outer side) settle it, and a walk takes over where rounding put
  // the boundary further away.
  int Boundary(double y, int lo, int hi) const {
    const double along = AlongRow(y);
    // Centre x where the edge crosses y, as a column: x - 0.5. Clamped before the integer
    // conversion rather than rounded with floor, a library call here.
    const double x = std::clamp(x0_ + (y - y0_) * dx_per_dy_ - 0.5, lo - 1.0, hi + 1.0);
    const int c = std::clamp(static_cast<int>(x) + (dy_ < 0 ? 1 : 0), lo, hi);
    const bool at = Passes(along, c);
    if (dy_ < 0) {  // passes: no ... no yes ... yes
      const bool before = c > lo && Passes(along, c - 1);
      if (!before) {
        if (at || c == hi) return at ? c : hi + 1;
        int b = c + 1;
        while (b <= hi && !Passes(along, b)) ++b;
        return b;
      }
      int b = c - 1;
      while (b > lo && Passes(along, b - 1)) --b;
      return b;
    }
    // passes: yes ... yes no ... no
    const bool after = c < hi && Passes(along, c + 1);
    if (!after) {
      if (at || c == lo) return at ? c : lo - 1;
      int b = c - 1;
      while (b >= lo && !Passes(along, b)) --b;
      return b;
    }
    int b = c + 1;
    while (b < hi && Passes(along, b + 1)) ++b;
    return b;
  }

  // out[r] = Boundary(first + r + 0.5, lo, hi) for r < rows.
  void Boundaries(int first, int rows, int lo, int hi, int* out) const {
#if MS_HAVE_AVX2_DISPATCH
    static const bool avx2 = __builtin_cpu_supports("avx2");
    if (avx2) return BoundariesAvx2(first, rows, lo, hi, out);
#endif
    for (int r = 0; r < rows; ++r) out[r] = Boundary(first + r + 0.5, lo, hi);
  }

 private:
#if MS_HAVE_AVX2_DISPATCH
  // Boundaries, 4 rows at a time: the common case (the guess and its outer neighbour settle it)
  // in AVX2 lanes, with the same operations on the same doubles (no fused multiply-adds: the
  // target has none), the rest (and any row whose crossing is NaN) by Boundary.
  __attribute__((target("avx2"))) void BoundariesAvx2(int first, int rows, int lo, int hi,
                                                      int* out) const {
    const __m256d ex = _mm256_set1_pd(ex_), first_y = _mm256_set1_pd(first_.y);
    const __m256d x0 = _mm256_set1_pd(x0_), y0 = _mm256_set1_pd(y0_);
    const __m256d slope = _mm256_set1_pd(dx_per_dy_), half = _mm256_set1_pd(0.5);
    const __m256d low = _mm256_set1_pd(lo - 1.0), high = _mm256_set1_pd(hi + 1.0);
    const __m128i lo4 = _mm_set1_epi32(lo), hi4 = _mm_set1_epi32(hi);
    const bool starts = dy_ < 0;  // the edge starts the covered columns; else it ends them
    const __m128i outer = _mm_set1_epi32(starts ? -1 : 1);  // the guess's outer neighbour
    const __m128i limit = starts ? lo4 : hi4;               // where that neighbour runs out
    const __m128i last = starts ? hi4 : lo4;                // the guess's other end
    const int none = starts ? hi + 1 : lo - 1;
    for (int r = 0; r < rows; r += 4) {
      const __m128i row = _mm_add_epi32(_mm_set1_epi32(first + r), _mm_setr_epi32(0, 1, 2, 3));
      const __m256d y = _mm256_add_pd(_mm256_cvtepi32_pd(row), half);
      const __m256d along = _mm256_mul_pd(ex, _mm256_sub_pd(y, first_y));
      __m256d x =
          _mm256_sub_pd(_mm256_add_pd(x0, _mm256_mul_pd(_mm256_sub_pd(y, y0), slope)), half);
      const int ordered = _mm256_movemask_pd(_mm256_cmp_pd(x, x, _CMP_ORD_Q));
      x = _mm256_blendv_pd(x, low, _mm256_cmp_pd(x, low, _CMP_LT_OQ));  // std::clamp
      x = _mm256_blendv_pd(x, high, _mm256_cmp_pd(high, x, _CMP_LT_OQ));
      __m128i c = _mm256_cvttpd_epi32(x);
      if (starts) c = _mm_add_epi32(c, _mm_set1_epi32(1));
      c = _mm_min_epi32(_mm_max_epi32(c, lo4), hi4);
      const int at = PassesAvx2(along, c);
      const int beyond =
          PassesAvx2(along, _mm_add_epi32(c, outer)) & ~Bits(_mm_cmpeq_epi32(c, limit));
      const int settled = ordered & ~beyond & (at | Bits(_mm_cmpeq_epi32(c, last)));
      alignas(16) int guess[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(guess), c);
      for (int k = 0; k < 4 && r + k < rows; ++k) {
        out[r + k] = (settled >> k & 1) ? ((at >> k & 1) ? guess[k] : none)
                                        : Boundary(first + r + k + 0.5, lo, hi);
      }
    }
  }

  // Passes(along, c) for 4 rows: one bit per row.
  __attribute__((target("avx2"))) int PassesAvx2(__m256d along, __m128i c) const {
    const __m256d ey = _mm256_set1_pd(ey_), zero = _mm256_setzero_pd();
    const __m256d centre = _mm256_add_pd(_mm256_cvtepi32_pd(c), _mm256_set1_pd(0.5));
    const __m256d w =
        _mm256_sub_pd(along, _mm256_mul_pd(ey, _mm256_sub_pd(centre, _mm256_set1_pd(first_.x))));
    const __m256d inside =
        negate_ ? _mm256_cmp_pd(w, zero, _CMP_LT_OQ) : _mm256_cmp_pd(w, zero, _CMP_GT_OQ);
    const int on_edge = top_left_ ? _mm256_movemask_pd(_mm256_cmp_pd(w, zero, _CMP_EQ_OQ)) : 0;
    return _mm256_movemask_pd(inside) | on_edge;
  }
  // One bit per lane of a comparison's result.
  __attribute__((target("avx2"))) static int Bits(__m128i m) {
    return _mm_movemask_ps(_mm_castsi128_ps(m));
  }
#endif

  bool negate_;                 // the edge runs from the lexicographically larger end: Edge negates
  bool top_left_;               // raster::TopLeft of the directed edge
  Point2 first_;                // the smaller end, which raster::Edge evaluates from
  double ex_, ey_;              // the other end - first_
  double dy_;                   // of the directed edge
  double x0_, y0_, dx_per_dy_;  // where the edge crosses a row: x0 + (y - y0) * dx_per_dy
};

constexpr int kRowsAtOnce = 32;

}  // namespace

void SpanRasterizer::FillRows(const Projected& t, int row_begin, int row_end) {
  // A pixel is covered when it passes the test of each edge. Along a row each edge's test is
  // monotone in the column (every rounding step of Edge is), so the covered columns are the
  // intersection of three half-lines, each found within the triangle's columns on its own.
  // An edge's boundaries are found for a batch of rows first: the rows do not depend on one
  // another, so the processor overlaps their work.
  const std::array<Point2, 3>& p = t.p;
  const std::array<RowEdge, 3> edges = {RowEdge(p[1], p[2]), RowEdge(p[2], p[0]),
                                        RowEdge(p[0], p[1])};
  const int lo = t.col_lo, hi = t.col_hi;
  for (int first = row_begin; first <= row_end; first += kRowsAtOnce) {
    const int rows = std::min(kRowsAtOnce, row_end - first + 1);
    std::array<int, kRowsAtOnce> begin, end;  // inclusive
    std::fill_n(begin.begin(), rows, lo);
    std::fill_n(end.begin(), rows, hi);
    for (const RowEdge& e : edges) {
      if (e.dy() == 0) {
        for (int r = 0; r < rows; ++r) {
          if (!e.Passes(e.AlongRow(first + r + 0.5), lo)) end[r] = lo - 1;
        }
        continue;
      }
      std::array<int, kRowsAtOnce> ends;
      e.Boundaries(first, rows, lo, hi, ends.data());
      if (e.dy() < 0) {
        for (int r = 0; r < rows; ++r) begin[r] = std::max(begin[r], ends[r]);
      } else {
        for (int r = 0; r < rows; ++r) end[r] = std::min(end[r], ends[r]);
      }
    }
    for (int r = 0; r < rows; ++r) {
      if (begin[r] > end[r]) continue;
      const int row = first + r;
      const size_t offset = static_cast<size_t>(row) * width_;
      FillSpan(inv_z_.data() + offset, keep_face_ ? face_.data() + offset : nullptr, begin[r],
               end[r] + 1, t.g0 + t.gx * 0.5 + t.gy * (row + 0.5), t.gx, t.face);
    }
  }
}

}  // namespace ms
