// The vertices the manifold's triangulation starts from, before any is inserted: the input
// points that are no near-duplicate of an earlier one, and the Steiner points around them
// (docs/design/manifold.md). DelaunayManifold::Build starts from these, and so do the tiles
// (tiles/tile_growth.h), which must agree with it point for point.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "manifold/delaunay_manifold.h"
#include "manifold/manifold_options.h"
#include "manifold/point_merging.h"
#include "manifold/steiner_points.h"

namespace ms {

// The bounding box of the points and the camera centres. Throws InputError for a position that
// is not finite, a camera index out of range, or nothing to bound.
void BoundPointsAndCameras(const std::vector<RayPoint>& points,
                           const std::vector<ManifoldCamera>& cameras, Eigen::Vector3d* lo,
                           Eigen::Vector3d* hi);

// The Steiner points of `options` around [lo, hi]: the box grid, then the graded points kept
// (all of them with GradedSteiner::kOn, those hidden in every view or in open air that rays
// cross densely with kHidden, none with kOff).
SteinerPoints PlaceSteinerPoints(const std::vector<RayPoint>& points,
                                 const std::vector<ManifoldCamera>& cameras,
                                 const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                 const ManifoldOptions& options);

// Whether a cell of Steiner points only is free space without rays (CellLabels::set_graded).
inline bool SteinerCellsFree(const ManifoldOptions& options) {
  return options.steiner_graded == GradedSteiner::kOn;
}

// The tolerance under which input points merge: options.merge_pixels of a pixel's footprint,
// at least options.merge_floor of the diagonal of the Steiner points' box.
MergeTolerance InputMergeTolerance(const std::vector<Eigen::Vector3d>& steiner,
                                   const ManifoldOptions& options);

}  // namespace ms
