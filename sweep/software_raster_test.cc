#include "sweep/software_raster.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

namespace ms {
namespace {

// Camera at the origin looking down +z with f = 1 and c = 0: a world point (u, v, 1) projects
// exactly to pixel coordinates (u, v), so tests can put edges exactly through pixel centres.
View UnitView(int width, int height) {
  View v;
  v.intrinsics = {width, height, 1, 1, 0, 0};
  return v;
}

// How often each pixel is covered when every triangle is drawn into its own cleared target.
std::vector<int> CoverageCounts(const View& view,
                                const std::vector<std::array<Eigen::Vector3d, 3>>& triangles) {
  SoftwareRasterizer raster(view, 1e-3, true);
  std::vector<int> counts(static_cast<size_t>(view.intrinsics.width) * view.intrinsics.height);
  for (const auto& t : triangles) {
    raster.Clear();
    raster.DrawTriangle(t[0], t[1], t[2], 0);
    for (size_t i = 0; i < counts.size(); ++i) counts[i] += raster.face()[i] >= 0;
  }
  return counts;
}

// A grid of quads over [x0, x1] x [y0, y1] on the plane z = 1, each split along a diagonal
// (alternating), both windings mixed.
std::vector<std::array<Eigen::Vector3d, 3>> Grid(double x0, double y0, double step, int n,
                                                 double jitter, std::mt19937* rng) {
  std::uniform_real_distribution<double> noise(-jitter, jitter);
  std::vector<Eigen::Vector3d> p;
  for (int r = 0; r <= n; ++r) {
    for (int c = 0; c <= n; ++c) {
      const bool border = r == 0 || c == 0 || r == n || c == n;
      const double jx = border ? 0 : noise(*rng), jy = border ? 0 : noise(*rng);
      p.emplace_back(x0 + c * step + jx, y0 + r * step + jy, 1);
    }
  }
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const int a = r * (n + 1) + c, b = a + 1, d = a + n + 1, e = d + 1;
      if ((r + c) % 2 == 0) {
        triangles.push_back({p[a], p[b], p[e]});
        triangles.push_back({p[a], p[d], p[e]});  // opposite winding
      } else {
        triangles.push_back({p[a], p[b], p[d]});
        triangles.push_back({p[b], p[e], p[d]});
      }
    }
  }
  return triangles;
}

TEST(SoftwareRasterizer, SharedEdgesThroughPixelCentresAreCoveredExactlyOnce) {
  const View view = UnitView(40, 30);
  std::mt19937 rng(1);
  // Vertices at pixel centres: every edge passes through pixel centres exactly.
  const auto triangles = Grid(4.5, 3.5, 4, 6, 0, &rng);
  const std::vector<int> counts = CoverageCounts(view, triangles);
  for (int row = 0; row < 30; ++row) {
    for (int col = 0; col < 40; ++col) {
      const double x = col + 0.5, y = row + 0.5;
      const bool interior = x > 4.5 && x < 28.5 && y > 3.5 && y < 27.5;
      const bool outside = x < 4.5 || x > 28.5 || y < 3.5 || y > 27.5;
      const int count = counts[row * 40 + col];
      if (interior) {
        EXPECT_EQ(count, 1) << col << "," << row;
      }
      if (outside) {
        EXPECT_EQ(count, 0) << col << "," << row;
      }
      EXPECT_LE(count, 1) << col << "," << row;
    }
  }
  // Top-left rule on the outer border: the left column (x = 4.5) and top row (y = 3.5) are in,
  // the right column (x = 28.5) and bottom row (y = 27.5) are out.
  EXPECT_EQ(counts[10 * 40 + 4], 1);
  EXPECT_EQ(counts[3 * 40 + 10], 1);
  EXPECT_EQ(counts[10 * 40 + 28], 0);
  EXPECT_EQ(counts[27 * 40 + 10], 0);
}

TEST(SoftwareRasterizer, JitteredMeshHasNoGapsOrOverlaps) {
  const View view = UnitView(64, 48);
  std::mt19937 rng(7);
  const auto triangles = Grid(5.25, 4.75, 5, 10, 0.75, &rng);  // jitter < 0.8 keeps orientations
  const std::vector<int> counts = CoverageCounts(view, triangles);
  for (int row = 0; row < 48; ++row) {
    for (int col = 0; col < 64; ++col) {
      const double x = col + 0.5, y = row + 0.5;
      const bool interior = x > 5.25 && x < 55.25 && y > 4.75 && y < 54.75;
      EXPECT_EQ(counts[row * 64 + col], interior ? 1 : 0) << col << "," << row;
    }
  }
}

// Ray through the pixel centre meets the triangle at camera depth >= near (Moller-Trumbore).
bool RayHits(const View& view, const std::array<Eigen::Vector3d, 3>& t, int col, int row,
             double near, Eigen::Vector3d* hit, double* edge_distance) {
  const Eigen::Vector3d o = view.Center();
  const Eigen::Vector3d d = view.PixelRay({col + 0.5, row + 0.5});
  const Eigen::Vector3d e1 = t[1] - t[0], e2 = t[2] - t[0];
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  const Eigen::Vector3d s = o - t[0];
  const double u = s.dot(p) / det;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  const double dist = e2.dot(q) / det;
  *edge_distance = std::min({u, v, 1 - u - v});
  *hit = o + dist * d;
  return u >= 0 && v >= 0 && u + v <= 1 && dist > 0 && view.ToCamera(*hit).z() >= near;
}

TEST(SoftwareRasterizer, PerspectiveCorrectAndNearClippedLikeRayCasting) {
  View view;
  view.intrinsics = {80, 60, 70, 65, 41.3, 29.7};
  view.R = RotationFromQuaternion(0.95, 0.1, -0.2, 0.05);
  view.SetCenter({0.2, -0.1, -3});
  const double near = 0.5;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coord(-1.5, 1.5);
  int covered = 0, clipped = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::array<Eigen::Vector3d, 3> t;
    for (auto& v : t) v = Eigen::Vector3d(coord(rng), coord(rng), coord(rng));
    if (trial % 4 == 0) t[0] = view.Center() + view.Axis() * 0.2 + Eigen::Vector3d(0.05, 0, 0);
    SoftwareRasterizer raster(view, near, true);
    raster.DrawTriangle(t[0], t[1], t[2], trial);
    clipped += view.ToCamera(t[0]).z() < near;
    for (int row = 0; row < 60; ++row) {
      for (int col = 0; col < 80; ++col) {
        Eigen::Vector3d hit;
        double edge;
        const bool expected = RayHits(view, t, col, row, near, &hit, &edge);
        const size_t i = raster.Index(col, row);
        const bool got = raster.face()[i] == trial;
        if (std::abs(edge) > 1e-6) {
          const Eigen::Vector3d c = view.ToCamera(hit);
          if (std::abs(c.z() - near) > 1e-6) {
            EXPECT_EQ(got, expected) << "trial " << trial << " pixel " << col << "," << row;
          }
        }
        if (got && expected) {
          ++covered;
          EXPECT_LT((raster.world()[i] - hit).norm(), 1e-9 * (1 + hit.norm()));
          EXPECT_NEAR(raster.depth()[i], view.ToCamera(hit).z(), 1e-9);
        }
      }
    }
  }
  EXPECT_GT(covered, 2000);
  EXPECT_GE(clipped, 5);  // the near plane was exercised
}

TEST(SoftwareRasterizer, DepthTestKeepsTheNearestAndTheFirstOnTies) {
  const View view = UnitView(20, 20);
  // Same footprint (x, y in [2, 12]) at depths 1 and 2: scale the far one by 2.
  const std::array<Eigen::Vector3d, 3> near_t = {
      Eigen::Vector3d(2, 2, 1), Eigen::Vector3d(12, 2, 1), Eigen::Vector3d(2, 12, 1)};
  std::array<Eigen::Vector3d, 3> far_t = near_t;
  for (auto& v : far_t) v *= 2;
  for (int order = 0; order < 2; ++order) {
    SoftwareRasterizer raster(view, 1e-3, true);
    if (order == 0) {
      raster.DrawTriangle(near_t[0], near_t[1], near_t[2], 1);
      raster.DrawTriangle(far_t[0], far_t[1], far_t[2], 2);
    } else {
      raster.DrawTriangle(far_t[0], far_t[1], far_t[2], 2);
      raster.DrawTriangle(near_t[0], near_t[1], near_t[2], 1);
    }
    EXPECT_EQ(raster.face()[raster.Index(4, 4)], 1);
    EXPECT_DOUBLE_EQ(raster.depth()[raster.Index(4, 4)], 1.0);
  }
  SoftwareRasterizer raster(view, 1e-3, true);
  raster.DrawTriangle(near_t[0], near_t[1], near_t[2], 5);
  raster.DrawTriangle(near_t[0], near_t[2], near_t[1], 6);  // same triangle, other winding
  EXPECT_EQ(raster.face()[raster.Index(4, 4)], 5);
  // Shadow-map mode keeps depth only.
  SoftwareRasterizer depth_only(view, 1e-3, false);
  depth_only.DrawTriangle(far_t[0], far_t[1], far_t[2], 0);
  EXPECT_TRUE(depth_only.world().empty());
  EXPECT_TRUE(depth_only.Covered(4, 4));
  EXPECT_FALSE(depth_only.Covered(15, 15));
  EXPECT_DOUBLE_EQ(depth_only.depth()[depth_only.Index(4, 4)], 2.0);
}

}  // namespace
}  // namespace ms
