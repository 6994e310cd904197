#include "manifold/point_merging.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace ms {
namespace {

// A uniform grid over the points, cells of the largest duplicate distance.
struct CellKey {
  int64_t x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  size_t operator()(const CellKey& k) const {
    return static_cast<size_t>(k.x * 73856093 ^ k.y * 19349663 ^ k.z * 83492791);
  }
};

}  // namespace

double DuplicateDistance(const Eigen::Vector3d& p, const std::vector<int32_t>& cameras,
                         const std::vector<ManifoldCamera>& all_cameras,
                         const MergeTolerance& tolerance) {
  double footprint = INFINITY;
  for (int32_t c : cameras) {
    const ManifoldCamera& camera = all_cameras[c];
    const double depth = camera.R.row(2).dot(p - camera.center);
    if (depth > 0 && camera.pixel_angle > 0)
      footprint = std::min(footprint, depth * camera.pixel_angle);
  }
  const double d = std::isfinite(footprint) ? tolerance.pixel_fraction * footprint : 0.0;
  return std::max(d, tolerance.floor);
}

std::vector<int32_t> NearDuplicateRepresentatives(const std::vector<RayPoint>& points,
                                                  const std::vector<ManifoldCamera>& cameras,
                                                  const MergeTolerance& tolerance) {
  const size_t n = points.size();
  std::vector<int32_t> representative(n);
  std::vector<double> distance(n);
  double cell = 0;
  for (size_t i = 0; i < n; ++i) {
    representative[i] = static_cast<int32_t>(i);
    distance[i] = DuplicateDistance(points[i].position, points[i].cameras, cameras, tolerance);
    cell = std::max(cell, distance[i]);
  }
  if (!(cell > 0)) return representative;
  const auto key = [cell](const Eigen::Vector3d& p) {
    return CellKey{static_cast<int64_t>(std::floor(p.x() / cell)),
                   static_cast<int64_t>(std::floor(p.y() / cell)),
                   static_cast<int64_t>(std::floor(p.z() / cell))};
  };
  // Points that stay, by cell; each point looks for an earlier one in its cell and the cells
  // its distance reaches (a duplicate is closer than the smaller distance, so this finds all).
  // The kept points of a cell as a chain through `next` (one allocation for all cells).
  std::unordered_map<CellKey, int32_t, CellHash> first_kept;
  first_kept.reserve(n);
  std::vector<int32_t> next(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = points[i].position;
    const CellKey k = key(p);
    // Only the neighbour cells that p's duplicate distance reaches into (usually none).
    int64_t from[3], to[3];
    const int64_t cell_index[3] = {k.x, k.y, k.z};
    for (int a = 0; a < 3; ++a) {
      from[a] = std::floor((p[a] - distance[i]) / cell) < cell_index[a] ? -1 : 0;
      to[a] = std::floor((p[a] + distance[i]) / cell) > cell_index[a] ? 1 : 0;
    }
    // The earliest kept point it duplicates (the order does not depend on the grid).
    int32_t found = -1;
    for (int64_t dx = from[0]; dx <= to[0]; ++dx) {
      for (int64_t dy = from[1]; dy <= to[1]; ++dy) {
        for (int64_t dz = from[2]; dz <= to[2]; ++dz) {
          auto it = first_kept.find({k.x + dx, k.y + dy, k.z + dz});
          if (it == first_kept.end()) continue;
          for (int32_t j = it->second; j >= 0; j = next[j]) {
            if ((found < 0 || j < found) &&
                (points[j].position - p).norm() < std::min(distance[i], distance[j])) {
              found = j;
            }
          }
        }
      }
    }
    if (found >= 0) {
      representative[i] = found;
    } else {
      auto [it, added] = first_kept.try_emplace(k, static_cast<int32_t>(i));
      if (!added) {
        next[i] = it->second;
        it->second = static_cast<int32_t>(i);
      }
    }
  }
  return representative;
}

}  // namespace ms
