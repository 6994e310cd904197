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
  // Points that stay, by cell; each point looks for an earlier one in the 27 cells around it.
  std::unordered_map<CellKey, std::vector<int32_t>, CellHash> kept;
  kept.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = points[i].position;
    const CellKey k = key(p);
    int32_t found = -1;
    for (int64_t dx = -1; dx <= 1 && found < 0; ++dx) {
      for (int64_t dy = -1; dy <= 1 && found < 0; ++dy) {
        for (int64_t dz = -1; dz <= 1 && found < 0; ++dz) {
          auto it = kept.find({k.x + dx, k.y + dy, k.z + dz});
          if (it == kept.end()) continue;
          for (int32_t j : it->second) {
            if ((points[j].position - p).norm() < std::min(distance[i], distance[j])) {
              found = j;
              break;
            }
          }
        }
      }
    }
    if (found >= 0) {
      representative[i] = found;
    } else {
      kept[k].push_back(static_cast<int32_t>(i));
    }
  }
  return representative;
}

}  // namespace ms
