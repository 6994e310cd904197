// Steiner points: where the triangulation gets vertices that are not input points.
//
// (1) A coarse grid on the faces of the bounding box of points and cameras, enlarged: every
//     camera lies inside the triangulation, and flat inputs still triangulate in 3D.
// (2) Optionally, graded points in the empty space: an octree whose leaves are as large as
//     their distance to the nearest input point allows, down to a few point spacings. Without
//     them the cells outside a dense surface all fan out to the few box points, and a viewing
//     ray crosses O(sqrt(n)) of those long thin cells; with them a ray crosses cells whose
//     size grows with the distance from the surface. They keep clear of the input points (at
//     least `clearance` x their own octree size, and never closer than a few point spacings),
//     so the Delaunay structure near the surface is unchanged.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace ms {

struct SteinerOptions {
  double margin = 0.5;            // box enlargement, x its diagonal
  int grid = 3;                   // points per box edge (>= 2)
  bool graded = false;            // add the graded points of (2)
  double clearance = 3.0;         // a leaf of half-size h has no input point within clearance*h
  double min_spacing_factor = 6;  // smallest leaf half-size = this x the median point spacing
};

struct SteinerPoints {
  std::vector<Eigen::Vector3d> points;
  Eigen::Vector3d box_min, box_max;  // the enlarged box
  int64_t graded = 0;                // how many of the points are graded ones
  // For each graded point (the last `graded` of `points`), its distance to the nearest input
  // point.
  std::vector<double> graded_clearance;
  double median_spacing = 0;  // of the input points (0 if fewer than 2)
};

SteinerPoints MakeSteinerPoints(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                                const std::vector<Eigen::Vector3d>& data,
                                const SteinerOptions& options);

// Static k-d tree over points: emptiness of a box and nearest neighbours (used above; exposed
// for tests).
class PointKdTree {
 public:
  explicit PointKdTree(std::vector<Eigen::Vector3d> points);
  bool AnyInBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  // Distance from `query` to the nearest point other than `exclude` (an index), or infinity.
  double NearestDistance(const Eigen::Vector3d& query, int64_t exclude = -1) const;
  size_t size() const { return points_.size(); }

 private:
  bool AnyInBox(size_t begin, size_t end, int depth, const Eigen::Vector3d& lo,
                const Eigen::Vector3d& hi) const;
  void Nearest(size_t begin, size_t end, int depth, const Eigen::Vector3d& query, int64_t exclude,
               double* best2) const;
  std::vector<Eigen::Vector3d> points_;  // in k-d order (median of each range at its middle)
  std::vector<int64_t> ids_;             // original index of each
};

}  // namespace ms
