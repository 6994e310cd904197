#include "coordinator/steiner_points.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

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

}  // namespace

std::vector<Eigen::Vector3d> MakeSteinerPoints(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                                               double margin, int grid) {
  grid = std::max(grid, 2);
  const Eigen::Vector3d extent = (max - min).cwiseMax(1e-12);
  // Enlarge by margin x diagonal, at least 1% of the largest side per axis (flat inputs).
  const double diagonal = extent.norm();
  const Eigen::Vector3d pad =
      Eigen::Vector3d::Constant(std::max(margin * diagonal, 0.01 * extent.maxCoeff()));
  const Eigen::Vector3d lo = min - pad, hi = max + pad;
  const Eigen::Vector3d step = (hi - lo) / (grid - 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < grid; ++i) {
    for (int j = 0; j < grid; ++j) {
      for (int k = 0; k < grid; ++k) {
        const bool on_surface =
            i == 0 || j == 0 || k == 0 || i == grid - 1 || j == grid - 1 || k == grid - 1;
        if (!on_surface) continue;
        Eigen::Vector3d p = lo + Eigen::Vector3d(i * step.x(), j * step.y(), k * step.z());
        // Jitter inwards only (stay inside the box so the hull stays the box's neighbourhood).
        for (int axis = 0; axis < 3; ++axis) {
          const int index = axis == 0 ? i : axis == 1 ? j : k;
          double offset = std::min(0.04 * step[axis], 0.1 * pad[axis]) * Jitter(i, j, k, axis);
          if (index == 0) offset = std::abs(offset);
          if (index == grid - 1) offset = -std::abs(offset);
          p[axis] += offset;
        }
        points.push_back(p);
      }
    }
  }
  return points;
}

}  // namespace ms
