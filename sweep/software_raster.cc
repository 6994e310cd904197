#include "sweep/software_raster.h"

#include <algorithm>
#include <cmath>

#include "base/check.h"
#include "sweep/raster_rules.h"

namespace ms {
using raster::Covers;
using raster::Edge;
using raster::Point2;

SoftwareRasterizer::SoftwareRasterizer(const View& view, double near, bool keep_world)
    : R_(view.R),
      t_(view.t),
      fx_(view.intrinsics.fx),
      fy_(view.intrinsics.fy),
      cx_(view.intrinsics.cx),
      cy_(view.intrinsics.cy),
      near_(near),
      width_(view.intrinsics.width),
      height_(view.intrinsics.height),
      keep_world_(keep_world) {
  MS_CHECK(width_ > 0 && height_ > 0 && near_ > 0) << "bad raster target";
  Clear();
}

void SoftwareRasterizer::Clear() {
  const size_t n = static_cast<size_t>(width_) * height_;
  depth_.assign(n, kEmpty);
  if (keep_world_) {
    world_.assign(n, Eigen::Vector3d::Zero());
    face_.assign(n, -1);
  }
}

void SoftwareRasterizer::DrawTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c, int32_t face) {
  const std::array<ClipVertex, 3> in = {ClipVertex{R_ * a + t_, a}, ClipVertex{R_ * b + t_, b},
                                        ClipVertex{R_ * c + t_, c}};
  const bool all_in =
      in[0].camera.z() >= near_ && in[1].camera.z() >= near_ && in[2].camera.z() >= near_;
  if (all_in) {
    DrawClipped(in[0], in[1], in[2], face);
    return;
  }
  // Sutherland-Hodgman against z >= near: at most 4 vertices, drawn as a fan.
  std::array<ClipVertex, 4> out;
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const ClipVertex& p = in[i];
    const ClipVertex& q = in[(i + 1) % 3];
    const bool p_in = p.camera.z() >= near_;
    const bool q_in = q.camera.z() >= near_;
    if (p_in) out[n++] = p;
    if (p_in != q_in) {
      const double s = (near_ - p.camera.z()) / (q.camera.z() - p.camera.z());
      ClipVertex x{p.camera + s * (q.camera - p.camera), p.world + s * (q.world - p.world)};
      x.camera.z() = near_;
      out[n++] = x;
    }
  }
  for (int i = 1; i + 1 < n; ++i) DrawClipped(out[0], out[i], out[i + 1], face);
}

void SoftwareRasterizer::DrawClipped(const ClipVertex& va, const ClipVertex& vb,
                                     const ClipVertex& vc, int32_t face) {
  std::array<const ClipVertex*, 3> v = {&va, &vb, &vc};
  std::array<Point2, 3> p;
  std::array<double, 3> inv_z;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& q = v[i]->camera;
    inv_z[i] = 1.0 / q.z();
    p[i] = {fx_ * q.x() * inv_z[i] + cx_, fy_ * q.y() * inv_z[i] + cy_};
    if (!std::isfinite(p[i].x) || !std::isfinite(p[i].y)) return;
  }
  double area = Edge(p[0], p[1], p[2]);
  if (area == 0 || !std::isfinite(area)) return;
  if (area < 0) {  // orient positively; no culling
    std::swap(p[1], p[2]);
    std::swap(v[1], v[2]);
    std::swap(inv_z[1], inv_z[2]);
  }
  const double min_x = std::min({p[0].x, p[1].x, p[2].x});
  const double max_x = std::max({p[0].x, p[1].x, p[2].x});
  const double min_y = std::min({p[0].y, p[1].y, p[2].y});
  const double max_y = std::max({p[0].y, p[1].y, p[2].y});
  // Pixel centres col + 0.5 within [min_x, max_x].
  const double col_lo = std::max(0.0, std::ceil(min_x - 0.5));
  const double col_hi = std::min(width_ - 1.0, std::floor(max_x - 0.5));
  const double row_lo = std::max(0.0, std::ceil(min_y - 0.5));
  const double row_hi = std::min(height_ - 1.0, std::floor(max_y - 0.5));
  if (col_lo > col_hi || row_lo > row_hi) return;
  for (int row = static_cast<int>(row_lo); row <= static_cast<int>(row_hi); ++row) {
    for (int col = static_cast<int>(col_lo); col <= static_cast<int>(col_hi); ++col) {
      const Point2 centre{col + 0.5, row + 0.5};
      const double w0 = Edge(p[1], p[2], centre);
      if (!Covers(w0, p[1], p[2])) continue;
      const double w1 = Edge(p[2], p[0], centre);
      if (!Covers(w1, p[2], p[0])) continue;
      const double w2 = Edge(p[0], p[1], centre);
      if (!Covers(w2, p[0], p[1])) continue;
      const double sum = w0 + w1 + w2;
      // Perspective-correct weights: screen barycentrics times 1/z, renormalised.
      const double q0 = w0 / sum * inv_z[0];
      const double q1 = w1 / sum * inv_z[1];
      const double q2 = w2 / sum * inv_z[2];
      const double q = q0 + q1 + q2;
      const double z = 1.0 / q;
      const size_t index = Index(col, row);
      if (!(z < depth_[index])) continue;
      depth_[index] = z;
      if (keep_world_) {
        world_[index] = (q0 * v[0]->world + q1 * v[1]->world + q2 * v[2]->world) * z;
        face_[index] = face;
      }
    }
  }
}

}  // namespace ms
