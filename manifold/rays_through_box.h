// Walking the viewing rays whose segment meets a box, each to its end point wherever it lies: a
// tile's rays, most of which end at points the tile does not hold (cell_ray_counts.h,
// tile_manifold.h). Internal to manifold/.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "base/error.h"
#include "manifold/cell_predicates.h"
#include "manifold/cell_ray_counts.h"
#include "manifold/ray_walker.h"

namespace ms::manifold_detail {

// Locates every camera; throws InputError for one outside the triangulation's hull.
inline void LocateCamerasInside(const std::vector<Eigen::Vector3d>& cameras, RayWalker* walker) {
  walker->LocateCameras(cameras);
  for (size_t c = 0; c < cameras.size(); ++c) {
    const CameraStart& start = walker->StartOf(static_cast<int>(c));
    if (start.type == Delaunay::OUTSIDE_CONVEX_HULL ||
        start.type == Delaunay::OUTSIDE_AFFINE_HULL) {
      throw InputError("camera " + std::to_string(c) + " lies outside the held points' hull");
    }
  }
}

// Walks every ray (camera -> points[ray.point]) whose closed segment meets [lo, hi] and calls
// count(cell, camera-side mask) for each cell it crosses (RayWalker::Walk). Throws InputError
// for a ray out of range. `walker` must have its cameras located.
template <typename Count>
void WalkRaysMeetingBox(const std::vector<Eigen::Vector3d>& points,
                        const std::vector<Eigen::Vector3d>& cameras,
                        const std::vector<ViewingRay>& rays, const Eigen::Vector3d& lo,
                        const Eigen::Vector3d& hi, RayWalker* walker, CellRayCountStats* stats,
                        Count&& count) {
  StampMarks marks(walker);
  WalkScratch scratch;
  for (const ViewingRay& ray : rays) {
    ++stats->rays;
    if (ray.camera < 0 || static_cast<size_t>(ray.camera) >= cameras.size() || ray.point < 0 ||
        static_cast<size_t>(ray.point) >= points.size()) {
      throw InputError("viewing ray (camera " + std::to_string(ray.camera) + ", point " +
                       std::to_string(ray.point) + ") is out of range");
    }
    double entry = 0;
    if (!SegmentMeetsBox(cameras[ray.camera], points[ray.point], lo, hi, &entry)) continue;
    ++stats->rays_walked;
    stats->cell_steps +=
        walker->WalkToPointWith(walker->StartOf(ray.camera), walker->camera_point(ray.camera),
                                ToPoint(points[ray.point]), marks, scratch, count);
  }
}

}  // namespace ms::manifold_detail
