#include "sweep/span_raster.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "base/check.h"
#include "sweep/raster_rules.h"
#include "sweep/vector_clones.h"

namespace ms {
using raster::Covers;
using raster::Edge;
using raster::Point2;

namespace {

// Nearest-wins fill of one span: 1/z = inv_z0 + col * inv_z_dx. Kept free of branches that
// stop the vectoriser.
MS_VECTOR_CLONES void FillSpan(float* __restrict inv_z, int32_t* __restrict faces, int begin,
                               int end, double inv_z0, double inv_z_dx, int32_t face) {
  for (int col = begin; col < end; ++col) {
    const float value = static_cast<float>(inv_z0 + col * inv_z_dx);
    const bool nearer = value > inv_z[col];
    inv_z[col] = nearer ? value : inv_z[col];
    if (faces != nullptr) faces[col] = nearer ? face : faces[col];
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

void SpanRasterizer::FillRows(const Projected& t, int row_begin, int row_end) {
  const std::array<Point2, 3>& p = t.p;
  // A pixel is covered when it passes the test of each edge. Along a row each edge's test is
  // monotone in the column (every rounding step of Edge is), so the covered columns are the
  // intersection of three half-lines: per edge, its boundary is guessed from where the edge
  // crosses the row's centre line and settled with the exact test a column or two around it.
  // The exact test is raster::Edge and raster::Covers with what does not change along the
  // edge (which end comes first, the fill rule) and along the row (the y product) taken out of
  // the loop: the same operations on the same values, so the same pixels.
  struct RowEdge {
    Point2 first;              // the lexicographically smaller end, as raster::Edge evaluates from
    double ex, ey;             // second - first
    bool negate;               // the edge runs from the larger end: Edge negates
    bool top_left;             // raster::TopLeft of the directed edge
    double dy;                 // of the directed edge (its sign says which side is inside)
    double x0, y0, dx_per_dy;  // the crossing of a row: x0 + (y - y0) * dx_per_dy
  };
  std::array<RowEdge, 3> edges;
  const std::array<std::array<int, 2>, 3> ends = {{{1, 2}, {2, 0}, {0, 1}}};
  for (int e = 0; e < 3; ++e) {
    const Point2& s = p[ends[e][0]];
    const Point2& q = p[ends[e][1]];
    const bool negate = raster::Before(q, s);
    const Point2& first = negate ? q : s;
    const Point2& second = negate ? s : q;
    const double dy = q.y - s.y;
    edges[e] = {first,
                second.x - first.x,
                second.y - first.y,
                negate,
                raster::TopLeft(s, q),
                dy,
                s.x,
                s.y,
                dy == 0 ? 0 : (q.x - s.x) / dy};
  }
  for (int row = row_begin; row <= row_end; ++row) {
    const double y = row + 0.5;
    int begin = t.col_lo, end = t.col_hi;  // inclusive
    for (const RowEdge& e : edges) {
      const double along = e.ex * (y - e.first.y);
      const auto passes = [&](int col) {
        const double w = along - e.ey * ((col + 0.5) - e.first.x);
        const bool inside = e.negate ? w < 0 : w > 0;
        return inside || (w == 0 && e.top_left);
      };
      if (e.dy == 0) {  // the same for the whole row
        if (!passes(begin)) end = begin - 1;
      } else {
        // Centre x where the edge crosses y, as a column: x - 0.5. The interior lies where
        // d(edge)/dx = -dy is positive: right of the crossing for dy < 0, left for dy > 0.
        // Only a guess (the walks below settle the column), so clamped before the integer
        // conversion rather than rounded with floor/ceil, which are library calls here.
        const double x = std::clamp(e.x0 + (y - e.y0) * e.dx_per_dy - 0.5, begin - 1.0, end + 1.0);
        int c = std::clamp(static_cast<int>(x) + (e.dy < 0 ? 0 : 1), begin, end);
        if (e.dy < 0) {  // the first column that passes
          if (passes(c)) {
            while (c > begin && passes(c - 1)) --c;
          } else {
            while (c <= end && !passes(c)) ++c;
          }
          begin = c;
        } else {  // the last column that passes
          if (passes(c)) {
            while (c < end && passes(c + 1)) ++c;
          } else {
            while (c >= begin && !passes(c)) --c;
          }
          end = c;
        }
      }
      if (begin > end) break;
    }
    if (begin > end) continue;
    const size_t offset = static_cast<size_t>(row) * width_;
    FillSpan(inv_z_.data() + offset, keep_face_ ? face_.data() + offset : nullptr, begin, end + 1,
             t.g0 + t.gx * 0.5 + t.gy * y, t.gx, t.face);
  }
}

}  // namespace ms
