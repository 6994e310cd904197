// Camera-only formats: Strecha .camera directories and Middlebury *_par.txt.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "base/error.h"
#include "scene/middlebury_io.h"
#include "scene/scene_io.h"
#include "scene/strecha_io.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::DataPath;
using testing::SharedData;

// Largest pixel distance between projections of `points` through same-named views.
double MaxProjectionDifference(const Scene& a, const Scene& b, const Scene& points) {
  std::map<std::string, const View*> by_name;
  for (const View& v : b.views) by_name[v.name] = &v;
  double worst = 0;
  for (const ScenePoint& p : points.points) {
    for (const Observation& o : p.observations) {
      const View& va = a.views[o.view];
      const auto vb = by_name.find(va.name);
      EXPECT_NE(vb, by_name.end()) << va.name;
      if (vb == by_name.end()) return 1e9;
      Eigen::Vector2d pa, pb;
      EXPECT_TRUE(va.Project(p.position, &pa));
      EXPECT_TRUE(vb->second->Project(p.position, &pb));
      worst = std::max(worst, (pa - pb).norm());
    }
  }
  return worst;
}

TEST(StrechaIo, Fixture) {
  const Scene scene = ReadScene(DataPath("strecha"));
  ASSERT_EQ(scene.views.size(), 2u);
  const View& a = scene.views[0];
  EXPECT_EQ(a.name, "a.png");
  EXPECT_EQ(a.intrinsics.fx, 50.5);
  EXPECT_EQ(a.intrinsics.fy, 51.5);
  EXPECT_EQ(a.intrinsics.cx, 31.75);
  EXPECT_EQ(a.intrinsics.cy, 24.25);
  EXPECT_EQ(a.intrinsics.width, 64);
  EXPECT_LT((a.Center() - Eigen::Vector3d(5, 0, 2)).norm(), 1e-14);
  // The camera looks at the origin.
  EXPECT_LT((a.Axis() + Eigen::Vector3d(5, 0, 2).normalized()).norm(), 1e-14);
  EXPECT_TRUE(scene.points.empty());
}

TEST(StrechaIo, RejectsDistortionAndSkew) {
  const std::string base = "50 0 32\n0 50 24\n0 0 1\n";
  const std::string rest = "1 0 0\n0 1 0\n0 0 1\n0 0 0\n64 48\n";
  EXPECT_NO_THROW(ParseStrechaCamera("x.camera", base + "0 0 0\n" + rest));
  try {
    ParseStrechaCamera("x.camera", base + "0.1 0 0\n" + rest);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "x.camera:4: distortion: only '0 0 0' is supported (the non-zero model is "
                 "undocumented)");
  }
  EXPECT_THROW(ParseStrechaCamera("x.camera", "50 1 32\n0 50 24\n0 0 1\n0 0 0\n" + rest),
               InputError);
  EXPECT_THROW(ParseStrechaCamera("x.camera", base + "0 0 0\n" + rest + "7\n"), InputError);
}

TEST(StrechaIo, FountainGroundTruthAgreesWithColmap) {
  if (!testing::HaveSharedData()) GTEST_SKIP() << "../shared/data not present";
  const Scene strecha = ReadScene(SharedData("fountain-P11/gt_dense_cameras"));
  ASSERT_EQ(strecha.views.size(), 11u);
  for (const View& v : strecha.views) {
    EXPECT_EQ(v.intrinsics.width, 3072);
    EXPECT_EQ(v.intrinsics.height, 2048);
    EXPECT_FALSE(v.image_path.empty()) << v.name;  // found in ../images
  }
  EXPECT_EQ(strecha.views[0].name, "0000.jpg");
  EXPECT_LT((strecha.views[0].Center() - Eigen::Vector3d(-7.28137, -7.57667, 0.204446)).norm(),
            1e-12);
  EXPECT_EQ(strecha.views[0].intrinsics.cx, 1520.69);
  // COLMAP triangulated its points with these poses: projections through either camera set
  // agree (the .camera files' 6 digits leave R a little off orthonormal).
  const Scene colmap = ReadScene(SharedData("fountain-P11/sparse"));
  const double difference = MaxProjectionDifference(colmap, strecha, colmap);
  EXPECT_LT(difference, 0.05);
  RecordProperty("max_projection_difference_px", std::to_string(difference));
}

TEST(MiddleburyIo, Fixture) {
  const Scene scene = ReadScene(DataPath("middlebury/tiny_par.txt"));
  ASSERT_EQ(scene.views.size(), 3u);
  const View& a = scene.views[0];
  EXPECT_EQ(a.name, "a.png");
  EXPECT_EQ(a.intrinsics.fx, 1520.4);
  EXPECT_EQ(a.intrinsics.fy, 1525.9);
  EXPECT_EQ(a.intrinsics.cx, 302.32);
  EXPECT_EQ(a.intrinsics.cy, 246.87);
  EXPECT_EQ(scene.views[2].intrinsics.width, 80);  // c.png
  EXPECT_EQ(scene.views[2].intrinsics.cx, 40.0);
  const double angle = 20 * M_PI / 180;
  EXPECT_LT(
      (a.Center() - Eigen::Vector3d(0.6 * std::cos(angle), 0.6 * std::sin(angle), 0.1)).norm(),
      1e-11);
}

TEST(MiddleburyIo, CountMustMatch) {
  const auto size = [](const std::string&) { return ImageSize{64, 48}; };
  const std::string line = "a.png 1 0 1 0 1 1 0 0 1 1 0 0 0 1 0 0 0 1 0 0 1\n";
  EXPECT_EQ(ParseMiddlebury("p_par.txt", "1\n" + line, size).views.size(), 1u);
  EXPECT_THROW(ParseMiddlebury("p_par.txt", "2\n" + line, size), InputError);
  EXPECT_THROW(ParseMiddlebury("p_par.txt", "1\n" + line + line, size), InputError);
}

class MiddleburyRealData : public ::testing::TestWithParam<const char*> {};

TEST_P(MiddleburyRealData, SixteenViewsAgreeWithColmap) {
  if (!testing::HaveSharedData()) GTEST_SKIP() << "../shared/data not present";
  const std::string set = GetParam();
  const std::string prefix = set.substr(0, set.find("SparseRing"));
  const Scene par = ReadScene(SharedData(set + "/" + prefix + "SR_par.txt"));
  ASSERT_EQ(par.views.size(), 16u);
  EXPECT_EQ(par.views[0].intrinsics.width, 640);
  EXPECT_EQ(par.views[0].intrinsics.height, 480);
  const Scene colmap = ReadScene(SharedData(set + "/sparse"));
  EXPECT_LT(MaxProjectionDifference(colmap, par, colmap), 0.01);
}

INSTANTIATE_TEST_SUITE_P(Sets, MiddleburyRealData,
                         ::testing::Values("templeSparseRing", "dinoSparseRing"));

TEST(CameraFiles, WriteReadRoundTrip) {
  testing::TempDir dir("camera_files");
  Scene scene = testing::MakeSyntheticScene(dir.path().string());
  scene.views[1].intrinsics.cx += 0.75;  // both formats hold any principal point
  scene.views[1].intrinsics.fy += 2;
  SceneWriteOptions lossy;
  lossy.allow_lossy = true;  // the points are dropped
  WriteScene(scene, dir / "cams", SceneFormat::kStrecha, lossy);
  WriteScene(scene, dir / "scene_par.txt", SceneFormat::kMiddlebury, lossy);
  Scene cameras_only = scene;
  cameras_only.points.clear();
  testing::ExpectScenesNear(cameras_only, ReadScene(dir / "cams", {}, SceneFormat::kStrecha),
                            1e-14);
  SceneReadOptions options;
  options.image_dir = dir.path().string();
  testing::ExpectScenesNear(cameras_only, ReadScene(dir / "scene_par.txt", options), 1e-15);
  EXPECT_THROW(WriteScene(scene, dir / "strict_par.txt", SceneFormat::kMiddlebury), InputError);
}

}  // namespace
}  // namespace ms
