#include "scene/bundler_io.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "base/error.h"
#include "base/file_util.h"
#include "scene/scene_io.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::DataPath;

void SortPoints(Scene* scene) {
  std::sort(scene->points.begin(), scene->points.end(),
            [](const ScenePoint& a, const ScenePoint& b) {
              return std::lexicographical_compare(a.position.data(), a.position.data() + 3,
                                                  b.position.data(), b.position.data() + 3);
            });
}

TEST(BundlerIo, ColmapExportMatchesItsSource) {
  // colmap.bundle.out + colmap.list.txt were written by COLMAP from colmap/export (centred
  // SIMPLE_RADIAL, RADIAL and SIMPLE_PINHOLE cameras): reading both must give the same scene.
  Scene bundler = ReadScene(DataPath("bundler/colmap.bundle.out"));
  Scene colmap = ReadScene(DataPath("colmap/export"));
  EXPECT_EQ(bundler.views[0].intrinsics.k1, -0.05);
  EXPECT_EQ(bundler.views[1].intrinsics.k2, -0.01);
  EXPECT_EQ(bundler.views[2].intrinsics.cx, 40.0);  // c.png is 80x60
  SortPoints(&bundler);
  SortPoints(&colmap);
  // COLMAP writes measurements with 6 significant digits.
  testing::ExpectScenesNear(colmap, bundler, 1e-12, 1e-4);
}

TEST(BundlerIo, ListPathNaming) {
  EXPECT_EQ(BundlerListPath("/a/bundle.out"), "/a/list.txt");
  EXPECT_EQ(BundlerListPath("/a/x.bundle.out"), "/a/x.list.txt");
  EXPECT_EQ(BundlerListPath("/a/model.out"), "/a/model.list.txt");
}

TEST(BundlerIo, SkipsUnregisteredCamerasAndFlipsAxes) {
  const std::string bundle =
      "# Bundle file v0.3\n3 1\n"
      "0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n"  // camera 0: not registered
      "100 0.1 -0.01\n1 0 0\n0 1 0\n0 0 1\n0 0 -5\n"
      "80 0 0\n1 0 0\n0 1 0\n0 0 1\n1 2 -6\n"
      "0 0 0\n1 2 3\n3 0 7 1 1 1 8 0 0 2 9 -2.5 4\n";
  const std::string list = "x.png\ny.png 0 100\nz.png\n";
  const Scene scene = ParseBundler("b.out", bundle, "list.txt", list, [](const std::string&) {
    return ImageSize{40, 30};
  });
  ASSERT_EQ(scene.views.size(), 2u);
  EXPECT_EQ(scene.views[0].name, "y.png");
  // Bundler looks down -z with y up: identity R becomes diag(1, -1, -1).
  EXPECT_EQ(scene.views[0].R, Eigen::Vector3d(1, -1, -1).asDiagonal().toDenseMatrix());
  EXPECT_EQ(scene.views[0].t, Eigen::Vector3d(0, 0, 5));
  EXPECT_EQ(scene.views[0].Center(), Eigen::Vector3d(0, 0, 5));
  // The origin is in front of camera 1 (at z = 5 looking down -z) and projects to the centre.
  ASSERT_EQ(scene.points[0].observations.size(), 2u);
  EXPECT_EQ(scene.points[0].observations[0].x, 20.0f);
  EXPECT_EQ(scene.points[0].observations[0].y, 15.0f);
  EXPECT_EQ(scene.points[0].observations[1].x, 17.5f);  // 20 + (-2.5)
  EXPECT_EQ(scene.points[0].observations[1].y, 11.0f);  // 15 - 4 (y up)
  Eigen::Vector2d px;
  ASSERT_TRUE(scene.views[0].Project({0, 0, 0}, &px));
  EXPECT_EQ(px, Eigen::Vector2d(20, 15));
}

TEST(BundlerIo, ListMustMatchCameraCount) {
  try {
    ParseBundler("b.out", "# Bundle file v0.3\n2 0\n", "list.txt", "x.png\n",
                 [](const std::string&) {
                   return ImageSize{40, 30};
                 });
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "list.txt: lists 1 images but b.out has 2 cameras");
  }
}

}  // namespace
}  // namespace ms
