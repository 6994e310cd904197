#include "manifold/steiner_sight.h"

#include <gtest/gtest.h>

namespace ms {
namespace {

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

TEST(HiddenInEveryView, KeepsOnlyWhatLiesBehindTheSeenPoints) {
  const std::vector<ManifoldCamera> cameras = {CameraAt(Eigen::Vector3d::Zero())};
  const std::vector<Eigen::Vector3d> candidates = {
      {-5, 0, 15},   // behind the wall
      {-5, 0, 5},    // in front of it
      {5, 0, 15},    // where the camera sees no point (the right half)
      {-5, 0, -15},  // behind the camera: no view holds it
  };
  const std::vector<uint8_t> hidden = HiddenInEveryView(candidates, LeftHalfWall(), cameras);
  EXPECT_EQ(hidden, (std::vector<uint8_t>{1, 0, 0, 0}));
}

TEST(HiddenInEveryView, OneViewThatSeesNoPointThereRefuses) {
  // Camera 1 stands beside camera 0 and observes only a patch far ahead of it: the candidate
  // behind the wall lies in its view, in a direction where it observes no point.
  std::vector<RayPoint> points = LeftHalfWall();
  for (double y = -2; y <= 2; y += 0.5) points.push_back({Eigen::Vector3d(-10, y, 100), {1}});
  const std::vector<ManifoldCamera> cameras = {CameraAt(Eigen::Vector3d::Zero()),
                                               CameraAt(Eigen::Vector3d(-10, 0, 5))};
  const std::vector<Eigen::Vector3d> behind = {{-5, 0, 15}};
  EXPECT_EQ(HiddenInEveryView(behind, LeftHalfWall(), {cameras[0]}), std::vector<uint8_t>{1});
  EXPECT_EQ(HiddenInEveryView(behind, points, cameras), std::vector<uint8_t>{0});
}

TEST(HiddenInEveryView, ADepthBetweenTheBinsPointsDecidesNothing) {
  // Two walls in the same bins, at z = 10 and z = 20: a candidate between them is neither in
  // front of the nearest nor behind the farthest, so no view votes for it.
  std::vector<RayPoint> points = LeftHalfWall();
  for (const RayPoint& p : LeftHalfWall()) {
    points.push_back({Eigen::Vector3d(p.position.x(), p.position.y(), 20), {0}});
  }
  const std::vector<ManifoldCamera> cameras = {CameraAt(Eigen::Vector3d::Zero())};
  const std::vector<Eigen::Vector3d> candidates = {{-5, 0, 15}, {-5, 0, 25}};
  EXPECT_EQ(HiddenInEveryView(candidates, points, cameras), (std::vector<uint8_t>{0, 1}));
}

}  // namespace
}  // namespace ms
