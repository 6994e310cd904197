#include "mesh/ray_caster.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace ms {

RayCaster::RayCaster(const Mesh& mesh) : vertices_(mesh.vertices) {
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    const Edges e = EdgesOf(face);
    if (e.e1.cross(e.e2).squaredNorm() == 0) continue;
    faces_.push_back({face, static_cast<int32_t>(f)});
    const Eigen::Vector3d& a = vertices_[face[0]];
    const Eigen::Vector3d b = a + e.e1, c = a + e.e2;
    boxes_.push_back(FloatBox3::Around(a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)));
  }
  faces_.shrink_to_fit();
  boxes_.shrink_to_fit();
  std::vector<int32_t> items(faces_.size());
  std::iota(items.begin(), items.end(), 0);
  tree_.Build(boxes_, std::move(items));
}

template <bool kAnyHit>
bool RayCaster::Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                         double t_min, double t_max, Hit* hit) const {
  bool found = false;
  tree_.QueryRay(origin, direction, t_min, &t_max, [&](int32_t i, double* nearest) {
    const Edges tri = EdgesOf(faces_[i].vertices);
    const Eigen::Vector3d p = direction.cross(tri.e2);
    const double det = tri.e1.dot(p);
    if (det == 0) return false;
    const double inv_det = 1 / det;
    const Eigen::Vector3d s = origin - vertices_[faces_[i].vertices[0]];
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
    hit->face = faces_[i].face;
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
