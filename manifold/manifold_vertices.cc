#include "manifold/manifold_vertices.h"

#include <cmath>
#include <string>
#include <utility>

#include "base/error.h"
#include "base/log.h"
#include "manifold/steiner_sight.h"

namespace ms {

void BoundPointsAndCameras(const std::vector<RayPoint>& points,
                           const std::vector<ManifoldCamera>& cameras, Eigen::Vector3d* lo,
                           Eigen::Vector3d* hi) {
  *lo = Eigen::Vector3d::Constant(INFINITY);
  *hi = -*lo;
  for (size_t i = 0; i < points.size(); ++i) {
    const RayPoint& p = points[i];
    if (!p.position.allFinite()) {
      throw InputError("point " + std::to_string(i) + ": position is not finite");
    }
    for (int32_t c : p.cameras) {
      if (c < 0 || c >= static_cast<int32_t>(cameras.size())) {
        throw InputError("point " + std::to_string(i) + ": camera " + std::to_string(c) +
                         " out of range (" + std::to_string(cameras.size()) + " cameras)");
      }
    }
    *lo = lo->cwiseMin(p.position);
    *hi = hi->cwiseMax(p.position);
  }
  for (const ManifoldCamera& c : cameras) {
    *lo = lo->cwiseMin(c.center);
    *hi = hi->cwiseMax(c.center);
  }
  if (!(lo->array() <= hi->array()).all()) throw InputError("no points and no cameras");
}

namespace {

// Keeps the box grid and, of the graded points, those hidden in every view that holds them
// and those in open air that rays cross densely (steiner_sight.h).
void KeepGradedPointsBySight(const std::vector<RayPoint>& points,
                             const std::vector<ManifoldCamera>& cameras, SteinerPoints* made) {
  const size_t box = made->points.size() - static_cast<size_t>(made->graded);
  const std::vector<Eigen::Vector3d> graded(made->points.begin() + box, made->points.end());
  const std::vector<SteinerSight> sight =
      ClassifyBySight(graded, made->graded_clearance, points, cameras, made->median_spacing);
  const std::vector<double> clearance = std::move(made->graded_clearance);
  made->graded_clearance.clear();
  made->points.resize(box);
  int64_t hidden = 0;
  for (size_t k = 0; k < graded.size(); ++k) {
    if (sight[k] == SteinerSight::kDrop) continue;
    made->points.push_back(graded[k]);
    made->graded_clearance.push_back(clearance[k]);
    hidden += sight[k] == SteinerSight::kHidden;
  }
  made->graded = static_cast<int64_t>(made->points.size() - box);
  spdlog::info(
      "manifold: graded Steiner points kept by sight: {} hidden in every view, {} in open air "
      "(of {})",
      hidden, made->graded - hidden, graded.size());
}

}  // namespace

SteinerPoints PlaceSteinerPoints(const std::vector<RayPoint>& points,
                                 const std::vector<ManifoldCamera>& cameras,
                                 const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                 const ManifoldOptions& options) {
  std::vector<Eigen::Vector3d> data(points.size());
  for (size_t i = 0; i < points.size(); ++i) data[i] = points[i].position;
  SteinerOptions steiner_options;
  steiner_options.margin = options.steiner_margin;
  steiner_options.grid = options.steiner_grid;
  const GradedSteiner scheme = options.steiner_graded;
  steiner_options.graded = scheme != GradedSteiner::kOff;
  steiner_options.clearance = options.steiner_clearance;
  steiner_options.min_spacing_factor = options.steiner_min_spacing;
  SteinerPoints made = MakeSteinerPoints(lo, hi, data, steiner_options);
  if (scheme == GradedSteiner::kHidden) KeepGradedPointsBySight(points, cameras, &made);
  return made;
}

MergeTolerance InputMergeTolerance(const std::vector<Eigen::Vector3d>& steiner,
                                   const ManifoldOptions& options) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const Eigen::Vector3d& s : steiner) {
    lo = lo.cwiseMin(s);
    hi = hi.cwiseMax(s);
  }
  MergeTolerance tolerance;
  // Relative to the box every vertex lies in, hence to every mesh's diagonal.
  tolerance.floor = options.merge_floor * (hi - lo).norm();
  tolerance.pixel_fraction = options.merge_pixels;
  return tolerance;
}

}  // namespace ms
