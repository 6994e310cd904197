#include "manifold/point_merging.h"

#include <gtest/gtest.h>

namespace ms {
namespace {

// A camera at the origin looking down +z with a focal length of 1000 px: at depth 10 a pixel is
// 0.01 wide.
std::vector<ManifoldCamera> OneCamera() {
  ManifoldCamera camera;
  camera.pixel_angle = 1e-3;
  return {camera};
}

RayPoint At(double x, double y, double z, std::vector<int32_t> cameras = {0}) {
  RayPoint p;
  p.position = Eigen::Vector3d(x, y, z);
  p.cameras = std::move(cameras);
  return p;
}

TEST(PointMerging, TheDuplicateDistanceIsAFractionOfThePixelFootprintAtTheDepth) {
  const MergeTolerance tolerance{0.5, 0};
  EXPECT_DOUBLE_EQ(DuplicateDistance({0, 0, 10}, {0}, OneCamera(), tolerance), 0.005);
  EXPECT_DOUBLE_EQ(DuplicateDistance({3, 0, 20}, {0}, OneCamera(), tolerance), 0.01);
  // Behind the camera, or seen by no camera: only the floor.
  EXPECT_DOUBLE_EQ(DuplicateDistance({0, 0, -10}, {0}, OneCamera(), {0.5, 1e-6}), 1e-6);
  EXPECT_DOUBLE_EQ(DuplicateDistance({0, 0, 10}, {}, OneCamera(), {0.5, 1e-6}), 1e-6);
}

TEST(PointMerging, PointsCloserThanTheDistanceMergeIntoTheFirst) {
  const std::vector<RayPoint> points = {At(0, 0, 10), At(1, 0, 10), At(0.004, 0, 10),
                                        At(0.006, 0, 10), At(1, 1e-8, 10)};
  const std::vector<int32_t> rep = NearDuplicateRepresentatives(points, OneCamera(), {0.5, 0});
  EXPECT_EQ(rep, (std::vector<int32_t>{0, 1, 0, 3, 1}));
}

TEST(PointMerging, TheSmallerOfTheTwoDistancesDecides) {
  // 0.007 apart: within the far point's distance (0.5 * 0.02), not the near one's (0.005).
  const std::vector<RayPoint> points = {At(0, 0, 10), At(0.007, 0, 10.0001)};
  std::vector<ManifoldCamera> cameras = OneCamera();
  ManifoldCamera far = cameras[0];
  far.center = Eigen::Vector3d(0, 0, -10);
  cameras.push_back(far);
  const std::vector<RayPoint> seen_far = {At(0, 0, 10, {1}), At(0.007, 0, 10.0001, {1})};
  EXPECT_EQ(NearDuplicateRepresentatives(points, cameras, {0.5, 0}), (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(NearDuplicateRepresentatives(seen_far, cameras, {0.5, 0}),
            (std::vector<int32_t>{0, 0}));
}

TEST(PointMerging, WithoutCamerasOnlyTheFloorMerges) {
  const std::vector<RayPoint> points = {At(0, 0, 0, {}), At(2e-7, 0, 0, {}), At(1e-5, 0, 0, {})};
  EXPECT_EQ(NearDuplicateRepresentatives(points, OneCamera(), {0.5, 1e-6}),
            (std::vector<int32_t>{0, 0, 2}));
  EXPECT_EQ(NearDuplicateRepresentatives(points, OneCamera(), {0.5, 0}),
            (std::vector<int32_t>{0, 1, 2}));
}

}  // namespace
}  // namespace ms
