#include "mesh/ray_caster.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace ms {

RayCaster::RayCaster(const Mesh& mesh) {
  triangles_.reserve(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    const Eigen::Vector3d& a = mesh.vertices[face[0]];
    const Eigen::Vector3d e1 = mesh.vertices[face[1]] - a, e2 = mesh.vertices[face[2]] - a;
    if (e1.cross(e2).squaredNorm() == 0) continue;
    triangles_.push_back({a, e1, e2, static_cast<int32_t>(f)});
    const Eigen::Vector3d b = a + e1, c = a + e2;
    boxes_.push_back(FloatBox3::Around(a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)));
  }
  std::vector<int32_t> items(triangles_.size());
  std::iota(items.begin(), items.end(), 0);
  tree_.Build(boxes_, std::move(items));
}

template <bool kAnyHit>
bool RayCaster::Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                         double t_min, double t_max, Hit* hit) const {
  bool found = false;
  tree_.QueryRay(origin, direction, t_min, &t_max, [&](int32_t i, double* nearest) {
    const Triangle& tri = triangles_[i];
    const Eigen::Vector3d p = direction.cross(tri.e2);
    const double det = tri.e1.dot(p);
    if (det == 0) return false;
    const double inv_det = 1 / det;
    const Eigen::Vector3d s = origin - tri.a;
    const double u = s.dot(p) * inv_det;
    if (u < 0 || u > 1) return false;
    const Eigen::Vector3d q = s.cross(tri.e1);
    const double v = direction.dot(q) * inv_det;
    if (v < 0 || u + v > 1) return false;
    const double t = tri.e2.dot(q) * inv_det;
    if (t <= t_min || t >= *nearest) return false;
    found = true;
    if (kAnyHit) return true;
    *nearest = t;
    hit->t = t;
    hit->face = tri.face;
    return false;
  });
  return found;
}

bool RayCaster::Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                          double t_min, double t_max, Hit* hit) const {
  Hit local;
  const bool found = Traverse<false>(origin, direction, t_min, t_max, &local);
  if (found && hit) *hit = local;
  return found;
}

bool RayCaster::Occluded(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                         double tolerance) const {
  const Eigen::Vector3d direction = to - from;
  const double length = direction.norm();
  if (length <= tolerance) return false;
  return Traverse<true>(from, direction, 0, 1 - tolerance / length, nullptr);
}

}  // namespace ms
