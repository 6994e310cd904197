#include "tools/ray_caster.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace ms {
namespace {

constexpr int kLeafSize = 4;

bool RayBox(const Eigen::Vector3d& origin, const Eigen::Vector3d& inverse_direction,
            const Eigen::Vector3d& box_min, const Eigen::Vector3d& box_max, double t_min,
            double t_max) {
  for (int axis = 0; axis < 3; ++axis) {
    double t0 = (box_min[axis] - origin[axis]) * inverse_direction[axis];
    double t1 = (box_max[axis] - origin[axis]) * inverse_direction[axis];
    if (t0 > t1) std::swap(t0, t1);
    // NaN (0 * inf on a slab boundary) leaves the interval unchanged: conservative.
    if (t0 > t_min) t_min = t0;
    if (t1 < t_max) t_max = t1;
    if (t_min > t_max) return false;
  }
  return true;
}

}  // namespace

RayCaster::RayCaster(const Mesh& mesh) {
  triangles_.reserve(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    const Eigen::Vector3d& a = mesh.vertices[face[0]];
    const Eigen::Vector3d e1 = mesh.vertices[face[1]] - a, e2 = mesh.vertices[face[2]] - a;
    if (e1.cross(e2).squaredNorm() == 0) continue;
    triangles_.push_back({a, e1, e2, static_cast<int32_t>(f)});
  }
  if (!triangles_.empty()) {
    nodes_.reserve(2 * triangles_.size() / kLeafSize + 2);
    Build(0, static_cast<int32_t>(triangles_.size()), 0);
  }
}

int32_t RayCaster::Build(int32_t first, int32_t count, int depth) {
  const int32_t index = static_cast<int32_t>(nodes_.size());
  nodes_.emplace_back();
  Eigen::Vector3d min = Eigen::Vector3d::Constant(INFINITY), max = -min;
  Eigen::Vector3d cmin = min, cmax = max;
  for (int32_t i = first; i < first + count; ++i) {
    const Triangle& t = triangles_[i];
    for (const Eigen::Vector3d& p :
         {t.a, Eigen::Vector3d(t.a + t.e1), Eigen::Vector3d(t.a + t.e2)}) {
      min = min.cwiseMin(p);
      max = max.cwiseMax(p);
    }
    const Eigen::Vector3d centroid = t.a + (t.e1 + t.e2) / 3;
    cmin = cmin.cwiseMin(centroid);
    cmax = cmax.cwiseMax(centroid);
  }
  nodes_[index].min = min;
  nodes_[index].max = max;
  int axis = 0;
  (cmax - cmin).maxCoeff(&axis);
  if (count <= kLeafSize || depth > 60 || cmax[axis] - cmin[axis] <= 0) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  const int32_t middle = first + count / 2;
  std::nth_element(triangles_.begin() + first, triangles_.begin() + middle,
                   triangles_.begin() + first + count,
                   [axis](const Triangle& x, const Triangle& y) {
                     return (3 * x.a + x.e1 + x.e2)[axis] < (3 * y.a + y.e1 + y.e2)[axis];
                   });
  const int32_t left = Build(first, middle - first, depth + 1);
  const int32_t right = Build(middle, first + count - middle, depth + 1);
  nodes_[index].first = left;  // nodes_ may have grown: index, not a reference
  nodes_[index].right = right;
  nodes_[index].count = 0;
  return index;
}

template <bool kAnyHit>
bool RayCaster::Traverse(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                         double t_min, double t_max, Hit* hit) const {
  if (nodes_.empty()) return false;
  const Eigen::Vector3d inverse = direction.cwiseInverse();
  int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  bool found = false;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!RayBox(origin, inverse, node.min, node.max, t_min, t_max)) continue;
    if (node.count > 0) {
      for (int32_t i = node.first; i < node.first + node.count; ++i) {
        const Triangle& tri = triangles_[i];
        const Eigen::Vector3d p = direction.cross(tri.e2);
        const double det = tri.e1.dot(p);
        if (det == 0) continue;
        const double inv_det = 1 / det;
        const Eigen::Vector3d s = origin - tri.a;
        const double u = s.dot(p) * inv_det;
        if (u < 0 || u > 1) continue;
        const Eigen::Vector3d q = s.cross(tri.e1);
        const double v = direction.dot(q) * inv_det;
        if (v < 0 || u + v > 1) continue;
        const double t = tri.e2.dot(q) * inv_det;
        if (t <= t_min || t >= t_max) continue;
        found = true;
        if (kAnyHit) return true;
        t_max = t;
        hit->t = t;
        hit->face = tri.face;
      }
    } else {
      if (top + 2 > 128) continue;  // depth is capped at 60 in Build; never happens
      stack[top++] = node.first;
      stack[top++] = node.right;
    }
  }
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
