// Near-duplicate points. SfM models hold points triangulated from different tracks a few 1e-8 m
// apart, and sweeps return points a hair from existing vertices; both are valid in exact
// arithmetic and make needles and slivers that floating-point tools (Open3D, MeshLab, refiners,
// slicers) see as self-intersections. Two points are duplicates when they are closer than a
// fraction of a pixel's footprint at their depth in the cameras that see them (what the images
// can tell apart at all), with a floor relative to the scene's size.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "manifold/delaunay_manifold.h"

namespace ms {

struct MergeTolerance {
  double pixel_fraction = 0.5;  // of a pixel's footprint at the point's depth
  double floor = 0;             // absolute, scene units
};

// The distance under which another point is a duplicate of `p` seen by `cameras`: the pixel
// fraction of the smallest footprint among the cameras in front of p, at least `floor`.
double DuplicateDistance(const Eigen::Vector3d& p, const std::vector<int32_t>& cameras,
                         const std::vector<ManifoldCamera>& all_cameras,
                         const MergeTolerance& tolerance);

// For each point, the index of the point it merges into: itself for a point that stays, an
// earlier point for a duplicate of it (closer than the smaller of the two duplicate distances).
// Greedy in index order, so the result is deterministic.
std::vector<int32_t> NearDuplicateRepresentatives(const std::vector<RayPoint>& points,
                                                  const std::vector<ManifoldCamera>& cameras,
                                                  const MergeTolerance& tolerance);

}  // namespace ms
