#include "manifold/steiner_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace ms {
namespace {

std::vector<Eigen::Vector3d> RandomPoints(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> points(n);
  for (Eigen::Vector3d& p : points) p = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return points;
}

// A dense sphere of radius 1 (a surface: empty space inside and out).
std::vector<Eigen::Vector3d> SpherePoints(int n) {
  std::vector<Eigen::Vector3d> points(n);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
    points[i] = Eigen::Vector3d(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return points;
}

double BruteNearest(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& q,
                    int64_t exclude = -1) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < points.size(); ++i) {
    if (static_cast<int64_t>(i) != exclude) best = std::min(best, (points[i] - q).norm());
  }
  return best;
}

TEST(PointKdTree, NearestAndBoxQueriesMatchBruteForce) {
  const std::vector<Eigen::Vector3d> points = RandomPoints(500, 3);
  const PointKdTree tree(points);
  const std::vector<Eigen::Vector3d> queries = RandomPoints(200, 4);
  for (const Eigen::Vector3d& q : queries) {
    EXPECT_DOUBLE_EQ(tree.NearestDistance(q), BruteNearest(points, q));
    const Eigen::Vector3d r = Eigen::Vector3d::Constant(0.1);
    bool any = false;
    for (const Eigen::Vector3d& p : points) {
      any |= ((p - q).cwiseAbs().array() <= 0.1).all();
    }
    EXPECT_EQ(tree.AnyInBox(q - r, q + r), any);
  }
  // Excluding a point's own index gives its nearest other point.
  for (int i = 0; i < 50; ++i) {
    EXPECT_DOUBLE_EQ(tree.NearestDistance(points[i], i), BruteNearest(points, points[i], i));
  }
}

TEST(SteinerPoints, BoxGridEnclosesEverythingAndIsTheOnlyPointsByDefault) {
  const std::vector<Eigen::Vector3d> data = SpherePoints(4000);
  SteinerOptions options;  // grid 3: 3^3 - 1 = 26 points on the box surface
  const SteinerPoints made =
      MakeSteinerPoints(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1), data, options);
  EXPECT_EQ(made.graded, 0);
  EXPECT_EQ(made.points.size(), 26u);
  EXPECT_TRUE((made.box_min.array() < -1).all() && (made.box_max.array() > 1).all());
  EXPECT_GT(made.median_spacing, 0);
  // Grid points sit on the box faces, jittered inwards by at most a tenth of the padding.
  const double pad = -1 - made.box_min.x();
  for (const Eigen::Vector3d& p : made.points) {
    EXPECT_TRUE((p.array() >= made.box_min.array()).all() &&
                (p.array() <= made.box_max.array()).all());
    const double to_face = std::min((p - made.box_min).minCoeff(), (made.box_max - p).minCoeff());
    EXPECT_LE(to_face, 0.1 * pad + 1e-12) << p.transpose();
    EXPECT_GT(p.cwiseAbs().maxCoeff(), 1 + 0.8 * pad) << "outside the data's box";
  }
}

TEST(SteinerPoints, GradedPointsKeepTheirClearanceAndAreDeterministic) {
  const std::vector<Eigen::Vector3d> data = SpherePoints(4000);
  SteinerOptions options;
  options.graded = true;
  options.min_spacing_factor = 2;
  const SteinerPoints made =
      MakeSteinerPoints(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1), data, options);
  ASSERT_GT(made.graded, 50);  // the empty space around the sphere gets points
  // A leaf of half-size h >= min_half has no point in its box of radius clearance*h; the
  // point is jittered by <= 0.1 h per axis, so it stays (clearance - 0.1) * min_half away.
  const double min_half = options.min_spacing_factor * made.median_spacing;
  const double guaranteed = (options.clearance - 0.1) * min_half;
  const PointKdTree tree(data);
  ASSERT_EQ(made.graded_clearance.size(), static_cast<size_t>(made.graded));
  const size_t first_graded = made.points.size() - made.graded;
  for (size_t i = first_graded; i < made.points.size(); ++i) {
    const Eigen::Vector3d& p = made.points[i];
    EXPECT_GE(tree.NearestDistance(p), guaranteed) << p.transpose();
    EXPECT_EQ(made.graded_clearance[i - first_graded], tree.NearestDistance(p));
    EXPECT_TRUE((p.array() > made.box_min.array()).all() &&
                (p.array() < made.box_max.array()).all());
  }
  const SteinerPoints again =
      MakeSteinerPoints(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1), data, options);
  ASSERT_EQ(again.points.size(), made.points.size());
  for (size_t i = 0; i < made.points.size(); ++i) EXPECT_EQ(again.points[i], made.points[i]);
}

}  // namespace
}  // namespace ms
