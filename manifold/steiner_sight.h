// Which graded Steiner points to keep, from what the cameras see (docs/design/manifold.md, "Steiner
// points"). Inside objects, under the ground and behind walls a graded point breaks the long
// cells that would otherwise join a facade to the far box points (viewing rays cross those
// cells and carve the corners of buildings away). In front of the surface, where few rays go,
// a graded point makes cells that no ray crosses, which then stand as blocks of matter before
// the surface; far from the surface, where many rays go, it only keeps the rays' walks short.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "manifold/delaunay_manifold.h"

namespace ms {

enum class SteinerSight : uint8_t {
  kDrop,
  // At least one camera sees input points in front of it, no camera whose view holds it sees
  // it in front of its points, and every such camera sees points near its direction.
  kHidden,
  // In front of the points some camera sees, at least kOpenAirSpacings median point spacings
  // from every input point, and crossed by rays densely: the cameras that see it in front send
  // at least kOpenAirRays rays (by the density of their points' directions) through a disc of
  // half its distance to the nearest point. The rays make its cells free; it only shortens
  // their walks.
  kOpenAir,
};

inline constexpr int kSightBins = 64;  // each camera's view cut into kSightBins^2 bins
inline constexpr double kOpenAirSpacings = 50;
inline constexpr double kOpenAirRays = 1000;

// Classifies each candidate by the depths of the input points in each camera's view bins: "in
// front" against the nearest depth of the bin and its 8 neighbours (and a bin that holds a
// point), "behind" against the farthest depth in the bin. `clearance[k]`: candidate k's
// distance to the nearest input point (SteinerPoints::graded_clearance); `median_spacing`: of
// the input points. Costs cameras x candidates projections.
std::vector<SteinerSight> ClassifyBySight(const std::vector<Eigen::Vector3d>& candidates,
                                          const std::vector<double>& clearance,
                                          const std::vector<RayPoint>& points,
                                          const std::vector<ManifoldCamera>& cameras,
                                          double median_spacing);

}  // namespace ms
