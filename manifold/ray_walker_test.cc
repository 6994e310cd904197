// The walk to a point that is not a vertex (a tile's ray to a point it does not hold) against
// an exhaustive search, and against the walk to the same point as a vertex.
#include "manifold/ray_walker.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

namespace ms::manifold_detail {
namespace {

using Crossings = std::map<CellKey, unsigned>;  // cell -> camera-side mask

// A unit cube's corners, random points inside and a 5x5x5 grid (co-spherical and coplanar
// points: segments that run through edges and vertices take the walk's degenerate steps).
std::vector<Eigen::Vector3d> Points() {
  std::vector<Eigen::Vector3d> points;
  for (int c = 0; c < 8; ++c) points.emplace_back(c & 1, c & 2 ? 1 : 0, c & 4 ? 1 : 0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  for (int i = 0; i < 150; ++i) points.emplace_back(u(rng), u(rng), u(rng));
  for (int x = 1; x <= 5; ++x) {
    for (int y = 1; y <= 5; ++y) {
      for (int z = 1; z <= 5; ++z) points.emplace_back(x / 6.0, y / 6.0, z / 6.0);
    }
  }
  return points;
}

Delaunay Triangulate(const std::vector<Eigen::Vector3d>& points) {
  Delaunay dt;
  for (size_t i = 0; i < points.size(); ++i) {
    const Vertex_handle v = dt.insert(ToPoint(points[i]));
    v->info().id = static_cast<int32_t>(i);
  }
  return dt;
}

// Every finite cell the open segment a -> b crosses, by the exact test.
Crossings Exhaustive(const Delaunay& dt, const Point& a, const Point& b) {
  Crossings crossed;
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    const FaceSides sides = ComputeFaceSides(c, a, b);
    if (SegmentCrossesCell(c, a, b, sides)) crossed[KeyOf(c)] = CameraSideMask(sides.a);
  }
  return crossed;
}

TEST(RayWalker, WalkToPointCrossesWhatTheExhaustiveSearchFinds) {
  const std::vector<Eigen::Vector3d> points = Points();
  const Delaunay dt = Triangulate(points);
  // Cameras in general position and one on a grid line (rays along edges from there).
  const std::vector<Eigen::Vector3d> cameras = {
      {0.11, 0.13, 0.07}, {0.93, 0.41, 0.52}, {0.47, 0.5, 2.0 / 6.0}, {0.31, 0.88, 0.91}};
  RayWalker walker(dt, cameras.size());
  walker.LocateCameras(cameras);
  StampMarks marks(&walker);
  WalkScratch scratch;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.02, 0.98);
  std::vector<Eigen::Vector3d> ends;
  for (int i = 0; i < 60; ++i) ends.emplace_back(u(rng), u(rng), u(rng));
  for (int x = 1; x <= 5; x += 2) ends.emplace_back(x / 6.0, 0.5, 2.0 / 6.0);  // on grid lines
  ends.emplace_back(0.5, 0.5, 0.5);  // a grid vertex as a point
  int walks = 0;
  for (size_t c = 0; c < cameras.size(); ++c) {
    for (const Eigen::Vector3d& end : ends) {
      Crossings walked;
      walker.WalkToPointWith(
          walker.StartOf(static_cast<int>(c)), walker.camera_point(c), ToPoint(end), marks, scratch,
          [&](const Cell_handle& cell, unsigned mask) {
            EXPECT_TRUE(walked.emplace(KeyOf(cell), mask).second) << "a cell visited twice";
          });
      EXPECT_EQ(walked, Exhaustive(dt, walker.camera_point(c), ToPoint(end)))
          << "camera " << c << " to (" << end.transpose() << ")";
      ++walks;
    }
  }
  EXPECT_EQ(walks, 4 * 64);
}

TEST(RayWalker, WalkToAVertexAsAPointCrossesTheSameCells) {
  const std::vector<Eigen::Vector3d> points = Points();
  const Delaunay dt = Triangulate(points);
  const std::vector<Eigen::Vector3d> cameras = {{0.11, 0.13, 0.07}, {0.47, 0.5, 2.0 / 6.0}};
  RayWalker walker(dt, cameras.size());
  walker.LocateCameras(cameras);
  int compared = 0;
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) {
    for (size_t c = 0; c < cameras.size(); ++c) {
      Crossings to_vertex, to_point;
      walker.WalkFromCamera(static_cast<int>(c), v, [&](const Cell_handle& cell, unsigned mask) {
        to_vertex[KeyOf(cell)] = mask;
      });
      StampMarks marks(&walker);
      WalkScratch scratch;
      walker.WalkToPointWith(
          walker.StartOf(static_cast<int>(c)), walker.camera_point(c), v->point(), marks, scratch,
          [&](const Cell_handle& cell, unsigned mask) { to_point[KeyOf(cell)] = mask; });
      ASSERT_EQ(to_vertex, to_point) << "camera " << c << " to point " << v->info().id;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 2 * static_cast<int>(points.size()));
}

}  // namespace
}  // namespace ms::manifold_detail
