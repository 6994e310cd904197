#include "manifold/steiner_points.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

namespace ms {
namespace {

// Deterministic value in [-1, 1] from integer coordinates (splitmix64 finaliser).
double Jitter(uint64_t a, uint64_t b, uint64_t c, uint64_t axis) {
  uint64_t x = a * 0x9E3779B97F4A7C15ull ^ (b + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull ^
               (c + 0x85EBCA77C2B2AE63ull) * 0x94D049BB133111EBull ^ axis * 0xD6E8FEB86659FD93ull;
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBull;
  x ^= x >> 31;
  return static_cast<double>(x >> 11) / static_cast<double>(1ull << 52) - 1.0;
}

// Points on the faces of the box [lo, hi], `grid` per edge, jittered along the faces (inwards
// on the axes where they sit on the boundary) so that no five are cospherical.
void AddBoxGrid(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& pad,
                int grid, std::vector<Eigen::Vector3d>* out) {
  const Eigen::Vector3d step = (hi - lo) / (grid - 1);
  for (int i = 0; i < grid; ++i) {
    for (int j = 0; j < grid; ++j) {
      for (int k = 0; k < grid; ++k) {
        const bool on_surface =
            i == 0 || j == 0 || k == 0 || i == grid - 1 || j == grid - 1 || k == grid - 1;
        if (!on_surface) continue;
        Eigen::Vector3d p = lo + Eigen::Vector3d(i * step.x(), j * step.y(), k * step.z());
        for (int axis = 0; axis < 3; ++axis) {
          const int index = axis == 0 ? i : axis == 1 ? j : k;
          double offset = std::min(0.04 * step[axis], 0.1 * pad[axis]) * Jitter(i, j, k, axis);
          if (index == 0) offset = std::abs(offset);
          if (index == grid - 1) offset = -std::abs(offset);
          p[axis] += offset;
        }
        out->push_back(p);
      }
    }
  }
}

}  // namespace

// ---- k-d tree ----

PointKdTree::PointKdTree(std::vector<Eigen::Vector3d> points) : points_(std::move(points)) {
  ids_.resize(points_.size());
  std::iota(ids_.begin(), ids_.end(), 0);
  // Build in place: at each range, the median along depth % 3 sits at the middle.
  struct Range {
    size_t begin, end;
    int depth;
  };
  std::vector<Range> stack{{0, points_.size(), 0}};
  std::vector<size_t> order(points_.size());
  std::iota(order.begin(), order.end(), 0);
  while (!stack.empty()) {
    const Range r = stack.back();
    stack.pop_back();
    if (r.end - r.begin <= 1) continue;
    const size_t mid = r.begin + (r.end - r.begin) / 2;
    const int axis = r.depth % 3;
    std::nth_element(order.begin() + r.begin, order.begin() + mid, order.begin() + r.end,
                     [&](size_t a, size_t b) { return points_[a][axis] < points_[b][axis]; });
    stack.push_back({r.begin, mid, r.depth + 1});
    stack.push_back({mid + 1, r.end, r.depth + 1});
  }
  std::vector<Eigen::Vector3d> sorted(points_.size());
  for (size_t i = 0; i < order.size(); ++i) {
    sorted[i] = points_[order[i]];
    ids_[i] = static_cast<int64_t>(order[i]);
  }
  points_ = std::move(sorted);
}

bool PointKdTree::AnyInBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
  return AnyInBox(0, points_.size(), 0, lo, hi);
}

bool PointKdTree::AnyInBox(size_t begin, size_t end, int depth, const Eigen::Vector3d& lo,
                           const Eigen::Vector3d& hi) const {
  if (begin >= end) return false;
  const size_t mid = begin + (end - begin) / 2;
  const Eigen::Vector3d& p = points_[mid];
  if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) return true;
  const int axis = depth % 3;
  if (lo[axis] <= p[axis] && AnyInBox(begin, mid, depth + 1, lo, hi)) return true;
  return hi[axis] >= p[axis] && AnyInBox(mid + 1, end, depth + 1, lo, hi);
}

double PointKdTree::NearestDistance(const Eigen::Vector3d& query, int64_t exclude) const {
  double best2 = std::numeric_limits<double>::infinity();
  Nearest(0, points_.size(), 0, query, exclude, &best2);
  return std::sqrt(best2);
}

void PointKdTree::Nearest(size_t begin, size_t end, int depth, const Eigen::Vector3d& query,
                          int64_t exclude, double* best2) const {
  if (begin >= end) return;
  const size_t mid = begin + (end - begin) / 2;
  if (ids_[mid] != exclude) *best2 = std::min(*best2, (points_[mid] - query).squaredNorm());
  const int axis = depth % 3;
  const double delta = query[axis] - points_[mid][axis];
  const bool left_first = delta < 0;
  if (left_first) {
    Nearest(begin, mid, depth + 1, query, exclude, best2);
    if (delta * delta < *best2) Nearest(mid + 1, end, depth + 1, query, exclude, best2);
  } else {
    Nearest(mid + 1, end, depth + 1, query, exclude, best2);
    if (delta * delta < *best2) Nearest(begin, mid, depth + 1, query, exclude, best2);
  }
}

// ---- Steiner points ----

SteinerPoints MakeSteinerPoints(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                                const std::vector<Eigen::Vector3d>& data,
                                const SteinerOptions& options) {
  SteinerPoints result;
  const int grid = std::max(options.grid, 2);
  const Eigen::Vector3d extent = (max - min).cwiseMax(1e-12);
  // Enlarge by margin x diagonal, at least 1% of the largest side per axis (flat inputs).
  const Eigen::Vector3d pad =
      Eigen::Vector3d::Constant(std::max(options.margin * extent.norm(), 0.01 * extent.maxCoeff()));
  result.box_min = min - pad;
  result.box_max = max + pad;
  AddBoxGrid(result.box_min, result.box_max, pad, grid, &result.points);
  if (data.size() < 2) return result;

  const PointKdTree tree(data);
  // Median nearest-neighbour distance over a deterministic sample.
  const size_t samples = std::min<size_t>(data.size(), 2000);
  std::vector<double> spacing;
  spacing.reserve(samples);
  for (size_t k = 0; k < samples; ++k) {
    const size_t i = k * data.size() / samples;
    const double d = tree.NearestDistance(data[i], static_cast<int64_t>(i));
    if (std::isfinite(d) && d > 0) spacing.push_back(d);
  }
  if (spacing.empty()) return result;
  std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
  result.median_spacing = spacing[spacing.size() / 2];
  if (!options.graded) return result;

  // Octree over the enlarged box's bounding cube: a node whose clearance box holds no input
  // point becomes a Steiner point at its (jittered) centre; others split down to min_half.
  const double min_half = options.min_spacing_factor * result.median_spacing;
  const Eigen::Vector3d center = 0.5 * (result.box_min + result.box_max);
  const double root_half = 0.5 * (result.box_max - result.box_min).maxCoeff();
  // Keep graded points off the box faces (those have the grid) by a fraction of the pad.
  const Eigen::Vector3d inner_lo = result.box_min + 0.25 * pad;
  const Eigen::Vector3d inner_hi = result.box_max - 0.25 * pad;
  const size_t cap = 2 * data.size() + 1000;  // a safeguard; grading stays far below it
  struct Node {
    Eigen::Vector3d center;
    double half;
    int level;
    int64_t ix, iy, iz;  // integer position at its level (for the jitter)
  };
  std::vector<Node> stack{{center, root_half, 0, 0, 0, 0}};
  while (!stack.empty() && static_cast<size_t>(result.graded) < cap) {
    const Node node = stack.back();
    stack.pop_back();
    const double reach = options.clearance * node.half;
    const Eigen::Vector3d r = Eigen::Vector3d::Constant(reach);
    if (node.level > 0 && !tree.AnyInBox(node.center - r, node.center + r)) {
      Eigen::Vector3d p = node.center;
      for (int axis = 0; axis < 3; ++axis) {
        p[axis] += 0.1 * node.half *
                   Jitter(static_cast<uint64_t>(node.ix) + 1000003ull * node.level,
                          static_cast<uint64_t>(node.iy), static_cast<uint64_t>(node.iz), axis);
      }
      if ((p.array() > inner_lo.array()).all() && (p.array() < inner_hi.array()).all()) {
        result.points.push_back(p);
        result.graded_clearance.push_back(tree.NearestDistance(p));
        ++result.graded;
      }
      continue;
    }
    if (node.half * 0.5 < min_half) continue;
    const double h = node.half * 0.5;
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      stack.push_back({node.center + Eigen::Vector3d(dx ? h : -h, dy ? h : -h, dz ? h : -h), h,
                       node.level + 1, 2 * node.ix + dx, 2 * node.iy + dy, 2 * node.iz + dz});
    }
  }
  return result;
}

}  // namespace ms
