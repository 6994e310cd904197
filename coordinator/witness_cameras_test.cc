// Which cameras see a swept point through the iteration's mesh.
#include "coordinator/witness_cameras.h"

#include <gtest/gtest.h>

#include <cmath>

#include "testing/test_meshes.h"

namespace ms {
namespace {

// A 64x48 camera 3.7 from the origin at `degrees` around z, looking at the origin (or away).
View CameraAt(double degrees, bool looking_away = false) {
  View v;
  v.intrinsics.width = 64;
  v.intrinsics.height = 48;
  v.intrinsics.fx = v.intrinsics.fy = 60;
  v.intrinsics.cx = 32;
  v.intrinsics.cy = 24;
  const double angle = degrees * M_PI / 180;
  const Eigen::Vector3d centre(3.7 * std::cos(angle), 3.7 * std::sin(angle), 0.1);
  const Eigen::Vector3d z = (looking_away ? 1.0 : -1.0) * centre.normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  v.R.row(0) = x;
  v.R.row(1) = z.cross(x);
  v.R.row(2) = z;
  v.SetCenter(centre);
  return v;
}

struct Fixture {
  Scene scene;
  Mesh mesh = test_meshes::Octahedron(0.3);
  std::vector<std::vector<int>> candidates;
  Fixture() {
    for (double degrees : {0.0, 30.0, 180.0}) scene.views.push_back(CameraAt(degrees));
    scene.views.push_back(CameraAt(10, /*looking_away=*/true));
    scene.views.push_back(CameraAt(60));
    candidates = WitnessCandidates(scene);
  }
};

// A point on the face x + y + z = 0.3 (the one that faces the cameras at 0 and 30 degrees),
// moved `inward` along the face's normal, matched by cameras 1 and 0.
RayPoint OnFrontFace(double inward) {
  RayPoint p;
  p.cameras = {1, 0};
  p.position = Eigen::Vector3d(0.2, 0.05, 0.05) - inward * Eigen::Vector3d(1, 1, 1).normalized();
  return p;
}

TEST(WitnessCameras, AddsTheCamerasThatSeeThePointInIdOrder) {
  Fixture f;
  const WitnessCameras witnesses(f.scene, f.candidates, f.mesh, 0.01);
  std::vector<RayPoint> points{OnFrontFace(0)};
  EXPECT_EQ(witnesses.Add(&points), 1);
  // Camera 2 would see it through the octahedron and camera 3 looks away; camera 4 faces the
  // point's face and comes after the matched ones.
  EXPECT_EQ(points[0].cameras, (std::vector<int32_t>{1, 0, 4}));
}

TEST(WitnessCameras, ToleranceLetsAPointJustBehindTheSurfaceBeSeen) {
  Fixture f;
  std::vector<RayPoint> near{OnFrontFace(0.02)};
  // Camera 4's ray runs 0.025 inside the octahedron; 1% of its length is 0.036.
  EXPECT_EQ(WitnessCameras(f.scene, f.candidates, f.mesh, 0.01).Add(&near), 1);
  std::vector<RayPoint> deep{OnFrontFace(0.02)};
  EXPECT_EQ(WitnessCameras(f.scene, f.candidates, f.mesh, 0.001).Add(&deep), 0);
  EXPECT_EQ(deep[0].cameras, (std::vector<int32_t>{1, 0}));
}

TEST(WitnessCameras, WithoutAMeshEveryCameraThatFramesThePointSeesIt) {
  Fixture f;
  const WitnessCameras witnesses(f.scene, f.candidates, Mesh(), 0.01);
  std::vector<RayPoint> points{OnFrontFace(0)};
  EXPECT_EQ(witnesses.Add(&points), 2);
  EXPECT_EQ(points[0].cameras, (std::vector<int32_t>{1, 0, 2, 4}));
}

TEST(WitnessCameras, CandidatesAreTheNearestCentresInAnyDirection) {
  Fixture f;
  ASSERT_EQ(f.candidates.size(), 5u);
  EXPECT_EQ(f.candidates[2], (std::vector<int>{0, 1, 3, 4}));  // behind it too, in id order
  Scene many;
  for (int i = 0; i < kWitnessCandidates + 8; ++i) many.views.push_back(CameraAt(i * 7.0));
  const std::vector<std::vector<int>> bounded = WitnessCandidates(many);
  EXPECT_EQ(static_cast<int>(bounded[0].size()), kWitnessCandidates);
  EXPECT_EQ(bounded[0].back(), static_cast<int>(many.views.size()) - 1);  // at -7 degrees
}

}  // namespace
}  // namespace ms
