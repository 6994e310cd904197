// Which graded Steiner points lie behind what every camera sees (docs/manifold.md, "Steiner
// points"). Inside objects, under the ground and behind walls a graded point breaks the long
// cells that would otherwise join a facade to the far box points (viewing rays cross those
// cells and carve the corners of buildings away); in front of the surface, where few rays go,
// a graded point makes cells that no ray crosses, which then stand as blocks of matter before
// the surface. So only the points hidden in every view that holds them are kept.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "manifold/delaunay_manifold.h"

namespace ms {

// For each candidate: whether at least one camera sees input points in front of it, no camera
// sees it in front of its points, and no camera whose view holds it sees no point near its
// direction. Each camera's view is cut into kSightBins x kSightBins bins of the depths of the
// points it observes: "in front" compares with the nearest depth of the bin and its 8
// neighbours, "behind" with the farthest depth of the bin itself.
std::vector<uint8_t> HiddenInEveryView(const std::vector<Eigen::Vector3d>& candidates,
                                       const std::vector<RayPoint>& points,
                                       const std::vector<ManifoldCamera>& cameras);

inline constexpr int kSightBins = 64;

}  // namespace ms
