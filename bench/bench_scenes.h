// Synthetic inputs for the benchmarks: points on a bumpy closed surface, a ring of cameras,
// each point seen by the k cameras that face it most directly. Deterministic for a seed.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "manifold/delaunay_manifold.h"

namespace ms::bench {

struct ManifoldBenchScene {
  std::vector<ManifoldCamera> cameras;
  std::vector<RayPoint> points;
};

// A unit-radius blob with bumps (radius 1 +- 0.15), `num_cameras` cameras on two rings at
// distance 3.5 looking at the centre; `rays_per_point` cameras per point.
ManifoldBenchScene MakeBlobScene(int64_t num_points, int num_cameras, int rays_per_point,
                                 uint64_t seed, double surface_offset = 0.0);

// Orders new points as the coordinator orders a sweep's results (coordinator.cc,
// InsertionOrder): by the first camera that sees them, then by pixel row and column in an
// 800x600 image of the normalised coordinates [u_min, u_max] x [v_min, v_max].
void SortLikeTheCoordinator(const std::vector<ManifoldCamera>& cameras,
                            std::vector<RayPoint>* points);

}  // namespace ms::bench
