#include "manifold/steiner_sight.h"

#include <gtest/gtest.h>

#include "manifold/steiner_points.h"

namespace ms {
namespace {

using Sight = SteinerSight;

// ClassifyBySight with each candidate's distance to the nearest point, as MakeSteinerPoints
// gives it; the median spacing defaults to the wall's (0.2).
std::vector<SteinerSight> Classify(const std::vector<Eigen::Vector3d>& candidates,
                                   const std::vector<RayPoint>& points,
                                   const std::vector<ManifoldCamera>& cameras,
                                   double median_spacing = 0.2) {
  std::vector<Eigen::Vector3d> positions;
  for (const RayPoint& p : points) positions.push_back(p.position);
  const PointKdTree tree(std::move(positions));
  std::vector<double> clearance;
  for (const Eigen::Vector3d& c : candidates) clearance.push_back(tree.NearestDistance(c));
  return ClassifyBySight(candidates, clearance, points, cameras, median_spacing);
}

// A camera at the origin looking down +z (identity rotation), a 90-degree view.
ManifoldCamera CameraAt(const Eigen::Vector3d& center) {
  ManifoldCamera camera;
  camera.center = center;
  return camera;
}

// A wall of points at z = 10 filling the left half of camera 0's view (x < 0), all seen by it.
std::vector<RayPoint> LeftHalfWall() {
  std::vector<RayPoint> points;
  for (double x = -9.9; x < 0; x += 0.2) {
    for (double y = -9.9; y < 10; y += 0.2) points.push_back({Eigen::Vector3d(x, y, 10), {0}});
  }
  return points;
}

TEST(ClassifyBySight, KeepsOnlyWhatLiesBehindTheSeenPoints) {
  const std::vector<ManifoldCamera> cameras = {CameraAt(Eigen::Vector3d::Zero())};
  const std::vector<Eigen::Vector3d> candidates = {
      {-5, 0, 15},   // behind the wall
      {-5, 0, 5},    // in front of it
      {5, 0, 15},    // where the camera sees no point (the right half)
      {-5, 0, -15},  // behind the camera: no view holds it
  };
  EXPECT_EQ(Classify(candidates, LeftHalfWall(), cameras),
            (std::vector<Sight>{Sight::kHidden, Sight::kDrop, Sight::kDrop, Sight::kDrop}));
}

TEST(ClassifyBySight, OneViewThatSeesNoPointThereRefuses) {
  // Camera 1 stands beside camera 0 and observes only a patch far ahead of it: the candidate
  // behind the wall lies in its view, in a direction where it observes no point.
  std::vector<RayPoint> points = LeftHalfWall();
  for (double y = -2; y <= 2; y += 0.5) points.push_back({Eigen::Vector3d(-10, y, 100), {1}});
  const std::vector<ManifoldCamera> cameras = {CameraAt(Eigen::Vector3d::Zero()),
                                               CameraAt(Eigen::Vector3d(-10, 0, 5))};
  const std::vector<Eigen::Vector3d> behind = {{-5, 0, 15}};
  EXPECT_EQ(Classify(behind, LeftHalfWall(), {cameras[0]}), std::vector<Sight>{Sight::kHidden});
  EXPECT_EQ(Classify(behind, points, cameras), std::vector<Sight>{Sight::kDrop});
}

TEST(ClassifyBySight, ADepthBetweenTheBinsPointsDecidesNothing) {
  // Two walls in the same bins, at z = 10 and z = 20: a candidate between them is neither in
  // front of the nearest nor behind the farthest, so no view votes for it.
  std::vector<RayPoint> points = LeftHalfWall();
  for (const RayPoint& p : LeftHalfWall()) {
    points.push_back({Eigen::Vector3d(p.position.x(), p.position.y(), 20), {0}});
  }
  const std::vector<ManifoldCamera> cameras = {CameraAt(Eigen::Vector3d::Zero())};
  const std::vector<Eigen::Vector3d> candidates = {{-5, 0, 15}, {-5, 0, 25}};
  EXPECT_EQ(Classify(candidates, points, cameras),
            (std::vector<Sight>{Sight::kDrop, Sight::kHidden}));
}

TEST(ClassifyBySight, KeepsOpenAirOnlyFarFromThePointsWhereRaysAreDense) {
  // A wall at z = 1000 with a point every 10 units, seen by camera 0 (about 9 points per bin).
  std::vector<RayPoint> points;
  for (double x = -900; x < 900; x += 10) {
    for (double y = -900; y < 900; y += 10) points.push_back({Eigen::Vector3d(x, y, 1000), {0}});
  }
  const std::vector<ManifoldCamera> cameras = {CameraAt(Eigen::Vector3d::Zero())};
  // 600 from the wall, 60 spacings: the rays toward the wall's points cross a disc of radius
  // 300 there by the ten thousand. 5 from the wall: too near.
  EXPECT_EQ(Classify({{0, 0, 400}, {0, 0, 995}}, points, cameras, 10.0),
            (std::vector<Sight>{Sight::kOpenAir, Sight::kDrop}));
  // 10 from the wall but 100 spacings of 0.1: far enough, yet about one ray crosses a disc of
  // radius 5 there.
  EXPECT_EQ(Classify({{0, 0, 990}}, points, cameras, 0.1), std::vector<Sight>{Sight::kDrop});
}

}  // namespace
}  // namespace ms
