// A bounding-volume hierarchy over triangles' boxes, in floats rounded outward (24 bytes a box
// against 48 in doubles), for the float cleanup's box searches and the CPU ray caster's rays.
// Both queries visit a superset of what exact boxes would give; callers test exactly.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "mesh/float_robustness.h"

namespace ms {

struct FloatBox3 {
  std::array<float, 3> lo, hi;
  // The smallest float box holding the double box [lo, hi].
  static FloatBox3 Around(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    FloatBox3 f;
    for (int d = 0; d < 3; ++d) {
      f.lo[d] = float_robustness_internal::FloatAtOrBelow(lo[d]);
      f.hi[d] = float_robustness_internal::FloatAtOrAbove(hi[d]);
    }
    return f;
  }
  static FloatBox3 Empty() {
    constexpr float inf = std::numeric_limits<float>::infinity();
    return {{inf, inf, inf}, {-inf, -inf, -inf}};
  }
  void Add(const FloatBox3& b) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], b.lo[d]);
      hi[d] = std::max(hi[d], b.hi[d]);
    }
  }
  bool Overlaps(const FloatBox3& b) const {
    for (int d = 0; d < 3; ++d) {
      if (lo[d] > b.hi[d] || b.lo[d] > hi[d]) return false;
    }
    return true;
  }
  // Whether the ray origin + t direction (`inverse`: 1 / direction) meets the box for some t in
  // [t_min, t_max]. NaN (0 x inf on a slab boundary) leaves the interval unchanged: conservative.
  bool MeetsRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& inverse, double t_min,
                double t_max) const {
    for (int axis = 0; axis < 3; ++axis) {
      double t0 = (lo[axis] - origin[axis]) * inverse[axis];
      double t1 = (hi[axis] - origin[axis]) * inverse[axis];
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > t_min) t_min = t0;
      if (t1 < t_max) t_max = t1;
      if (t_min > t_max) return false;
    }
    return true;
  }
};

// The tree over the items (indices into `boxes`) alive when it is built: median splits on the
// longest axis of the box centres, leaves of at most 8 items. Items made later are the caller's
// to scan.
class FaceTree {
 public:
  void Build(const std::vector<FloatBox3>& boxes, std::vector<int32_t> faces) {
    boxes_ = &boxes;
    order_ = std::move(faces);
    nodes_.clear();
    if (!order_.empty()) BuildNode(0, static_cast<int32_t>(order_.size()));
  }

  // visit(item) for every item whose box overlaps `box`.
  template <typename Visit>
  void Query(const FloatBox3& box, Visit&& visit) const {
    if (nodes_.empty()) return;
    std::vector<int32_t> stack{0};
    while (!stack.empty()) {
      const Node& node = nodes_[stack.back()];
      stack.pop_back();
      if (!node.box.Overlaps(box)) continue;
      if (node.left < 0) {
        for (int32_t i = node.begin; i < node.end; ++i) {
          if ((*boxes_)[order_[i]].Overlaps(box)) visit(order_[i]);
        }
      } else {
        stack.push_back(node.left);
        stack.push_back(node.right);
      }
    }
  }

  // visit(item, &t_max) for every item whose box the ray origin + t direction meets for t in
  // [t_min, *t_max]; a visit may lower *t_max (a nearest-hit search) or return true to stop
  // (any hit). Returns whether a visit stopped it.
  template <typename Visit>
  bool QueryRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                double* t_max, Visit&& visit) const {
    if (nodes_.empty()) return false;
    const Eigen::Vector3d inverse = direction.cwiseInverse();
    std::vector<int32_t> stack{0};
    while (!stack.empty()) {
      const Node& node = nodes_[stack.back()];
      stack.pop_back();
      if (!node.box.MeetsRay(origin, inverse, t_min, *t_max)) continue;
      if (node.left < 0) {
        for (int32_t i = node.begin; i < node.end; ++i) {
          if ((*boxes_)[order_[i]].MeetsRay(origin, inverse, t_min, *t_max) &&
              visit(order_[i], t_max)) {
            return true;
          }
        }
      } else {
        stack.push_back(node.left);
        stack.push_back(node.right);
      }
    }
    return false;
  }

 private:
  struct Node {
    FloatBox3 box;
    int32_t begin = 0, end = 0, left = -1, right = -1;
  };

  int32_t BuildNode(int32_t begin, int32_t end) {
    const int32_t index = static_cast<int32_t>(nodes_.size());
    nodes_.push_back({});
    FloatBox3 box = FloatBox3::Empty(), centres = FloatBox3::Empty();
    for (int32_t i = begin; i < end; ++i) {
      const FloatBox3& b = (*boxes_)[order_[i]];
      box.Add(b);
      FloatBox3 centre;
      for (int d = 0; d < 3; ++d) centre.lo[d] = centre.hi[d] = (b.lo[d] + b.hi[d]) / 2;
      centres.Add(centre);
    }
    nodes_[index].box = box;
    nodes_[index].begin = begin;
    nodes_[index].end = end;
    if (end - begin <= 8) return index;
    int axis = 0;
    for (int d = 1; d < 3; ++d) {
      if (centres.hi[d] - centres.lo[d] > centres.hi[axis] - centres.lo[axis]) axis = d;
    }
    const int32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](int32_t a, int32_t b) {
                       const FloatBox3& x = (*boxes_)[a];
                       const FloatBox3& y = (*boxes_)[b];
                       return x.lo[axis] + x.hi[axis] < y.lo[axis] + y.hi[axis];
                     });
    const int32_t left = BuildNode(begin, mid);
    const int32_t right = BuildNode(mid, end);
    nodes_[index].left = left;
    nodes_[index].right = right;
    return index;
  }

  const std::vector<FloatBox3>* boxes_ = nullptr;
  std::vector<int32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace ms
