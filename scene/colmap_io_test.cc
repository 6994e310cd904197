#include "scene/colmap_io.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "base/error.h"
#include "base/file_util.h"
#include "scene/scene_io.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::DataPath;
using testing::SharedData;

ColmapFiles FixtureFiles() {
  ColmapFiles files;
  files.cameras_name = "cameras.txt";
  files.images_name = "images.txt";
  files.points_name = "points3D.txt";
  files.cameras = ReadFileToString(DataPath("colmap/text/cameras.txt"));
  files.images = ReadFileToString(DataPath("colmap/text/images.txt"));
  files.points = ReadFileToString(DataPath("colmap/text/points3D.txt"));
  return files;
}

std::string ErrorOf(const ColmapFiles& files) {
  try {
    ParseColmapModel(files, false);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ColmapIo, TextFixtureHasExactValues) {
  const Scene scene = ReadScene(DataPath("colmap/text"));
  ASSERT_EQ(scene.views.size(), 6u);
  // Views are ordered by image id: 1 d, 2 e, 3 b, 5 c, 7 a, 9 f.
  const char* names[] = {"d.png", "e.png", "b.png", "c.png", "a.png", "f.png"};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(scene.views[i].name, names[i]);
  // Image 1 uses RADIAL 64 48 50 32 24 -0.1 0.02.
  const Intrinsics& radial = scene.views[0].intrinsics;
  EXPECT_EQ(radial.width, 64);
  EXPECT_EQ(radial.fx, 50);
  EXPECT_EQ(radial.fy, 50);
  EXPECT_EQ(radial.cx, 32);
  EXPECT_EQ(radial.k1, -0.1);
  EXPECT_EQ(radial.k2, 0.02);
  EXPECT_EQ(radial.p1, 0);
  const Eigen::Matrix3d R = RotationFromQuaternion(0.15928040038202265, 0.2040025788119434,
                                                   -0.7613479890012472, 0.594442546875622);
  EXPECT_EQ(scene.views[0].R, R);
  EXPECT_EQ(scene.views[0].t.z(), 4.123105625617661);
  // PINHOLE 64 48 52 51 31.5 24.5 (image 3), OPENCV and FULL_OPENCV (images 2, 9).
  EXPECT_EQ(scene.views[2].intrinsics.fy, 51);
  EXPECT_EQ(scene.views[2].intrinsics.cx, 31.5);
  EXPECT_EQ(scene.views[1].intrinsics.p2, -0.002);
  EXPECT_EQ(scene.views[1].intrinsics.k3, 0);
  EXPECT_EQ(scene.views[5].intrinsics.k3, 0.003);
  EXPECT_EQ(scene.views[3].intrinsics.width, 80);
  EXPECT_EQ(scene.views[3].intrinsics.k1, -0.1);  // SIMPLE_RADIAL
  // Points ordered by id: 7, 8, 13, 42, 55, 100. Point 7 = (0.1, 0.35, -0.2), colour 7 8 9.
  ASSERT_EQ(scene.points.size(), 6u);
  const ScenePoint& p7 = scene.points[0];
  EXPECT_EQ(p7.position, Eigen::Vector3d(0.1, 0.35, -0.2));
  EXPECT_EQ(p7.color, (std::array<uint8_t, 3>{7, 8, 9}));
  ASSERT_EQ(p7.observations.size(), 5u);
  EXPECT_EQ(p7.observations[4].view, 4);  // image 7 = a.png
  EXPECT_EQ(p7.observations[4].x, 36.29490280151367f);
  EXPECT_EQ(p7.observations[4].y, 26.678571701049805f);
  // Point 42 is seen twice in image 3; the first feature is kept.
  const ScenePoint& p42 = scene.points[3];
  ASSERT_EQ(p42.observations.size(), 5u);
  EXPECT_EQ(p42.observations[2].view, 2);
  EXPECT_EQ(p42.observations[2].x, 34.95951461791992f);
  // Images found in tests/data/images (two folders up, images/); e.png and f.png do not exist.
  EXPECT_TRUE(std::filesystem::exists(scene.views[4].image_path)) << scene.views[4].image_path;
  EXPECT_EQ(scene.views[1].image_path, "");
}

TEST(ColmapIo, ProjectionsMatchTheFixtureObservations) {
  // The fixture's features are projections through each camera model (incl. distortion).
  const Scene scene = ReadScene(DataPath("colmap/text"));
  for (const ScenePoint& p : scene.points) {
    for (const Observation& o : p.observations) {
      Eigen::Vector2d px;
      ASSERT_TRUE(scene.views[o.view].Project(p.position, &px));
      EXPECT_NEAR(px.x(), o.x, 1e-4) << scene.views[o.view].name;
      EXPECT_NEAR(px.y(), o.y, 1e-4);
    }
  }
}

TEST(ColmapIo, BinaryWrittenByColmapMatchesText) {
  const Scene text = ReadScene(DataPath("colmap/text"));
  const Scene binary = ReadScene(DataPath("colmap/bin"));
  testing::ExpectScenesNear(text, binary, 1e-15);
}

TEST(ColmapIo, ErrorsNameFileLineAndField) {
  ColmapFiles files = FixtureFiles();
  files.cameras = "1 PINHOLE 64 48 50 50 32\n";
  EXPECT_EQ(ErrorOf(files),
            "cameras.txt:1: PARAMS: model PINHOLE has 4 parameters, the line has 3");
  files = FixtureFiles();
  files.cameras += "9 FANCY 1 1 1\n";
  EXPECT_EQ(ErrorOf(files), "cameras.txt:11: MODEL: unknown camera model 'FANCY'");
  files = FixtureFiles();
  files.points += "5 1 2 nan 0 0 0 0\n";
  EXPECT_EQ(ErrorOf(files), "points3D.txt:10: Z: value 'nan' is not finite");
  files = FixtureFiles();
  files.points += "5 1 2 3 0 0 0 0 999 0\n";
  EXPECT_EQ(ErrorOf(files),
            "points3D.txt:10: point 5: track refers to image 999, which is not in images.txt");
}

TEST(ColmapIo, UnsupportedModelIsNamedWhenUsed) {
  ColmapFiles files = FixtureFiles();
  // The unused OPENCV_FISHEYE camera 8 is fine; make image 9 use it.
  const size_t at = files.images.find(" 6 f.png");
  ASSERT_NE(at, std::string::npos);
  files.images.replace(at, 8, " 8 f.png");
  const std::string error = ErrorOf(files);
  EXPECT_NE(error.find("camera model OPENCV_FISHEYE is not supported"), std::string::npos) << error;
  EXPECT_EQ(error.rfind("cameras.txt:10: camera 8", 0), 0u) << error;
}

TEST(ColmapIo, WriteReadRoundTripIsExact) {
  const Scene scene = ReadScene(DataPath("colmap/text"));
  testing::TempDir dir("colmap_rt");
  for (bool binary : {false, true}) {
    const std::string out = dir / (binary ? "bin" : "txt");
    WriteColmapModel(scene, out, binary, {});
    const Scene back = ReadColmapModel(out, binary, {});
    testing::ExpectScenesNear(scene, back, 1e-15);
  }
  // Identical intrinsics share one camera; six different ones give six.
  const std::string cameras = ReadFileToString(dir / "txt/cameras.txt");
  EXPECT_NE(cameras.find("# Number of cameras: 6"), std::string::npos);
  EXPECT_NE(cameras.find("1 RADIAL 64 48 50 32 24 -0.1 0.02\n"), std::string::npos) << cameras;
  EXPECT_NE(cameras.find("FULL_OPENCV 64 48 50 51 32 24 -0.1 0.01 0.001 -0.002 0.003 0 0 0"),
            std::string::npos);
}

TEST(ColmapIo, ColmapReadsWhatWeWrite) {
  if (std::system("colmap help > /dev/null 2>&1") != 0) GTEST_SKIP() << "colmap not installed";
  const Scene scene = ReadScene(DataPath("colmap/text"));
  testing::TempDir dir("colmap_compat");
  WriteColmapModel(scene, dir / "ours", true, {});
  std::filesystem::create_directories(dir / "theirs");
  const std::string command = "colmap model_converter --input_path " + (dir / "ours") +
                              " --output_path " + (dir / "theirs") +
                              " --output_type TXT > /dev/null 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  testing::ExpectScenesNear(scene, ReadColmapModel(dir / "theirs", false, {}), 1e-15);
}

class ColmapRealData : public ::testing::TestWithParam<std::tuple<const char*, size_t, size_t>> {};

TEST_P(ColmapRealData, TextAndBinaryGiveIdenticalScenes) {
  if (!testing::HaveSharedData()) GTEST_SKIP() << "../shared/data not present";
  const auto [set, num_views, num_points] = GetParam();
  const std::string model = SharedData(std::string(set) + "/sparse");
  const Scene text = ReadScene(model, {}, SceneFormat::kColmapText);
  const Scene binary = ReadScene(model, {}, SceneFormat::kColmapBinary);
  EXPECT_EQ(text.views.size(), num_views);
  EXPECT_EQ(text.points.size(), num_points);
  testing::ExpectScenesNear(text, binary, 0.0);
  for (const View& v : text.views) {
    EXPECT_TRUE(std::filesystem::is_regular_file(v.image_path)) << v.name << " -> " << v.image_path;
  }
  // The set folder itself is detected too (sparse/ inside it).
  EXPECT_EQ(DetectSceneFormat(SharedData(set)), SceneFormat::kColmapBinary);
}

INSTANTIATE_TEST_SUITE_P(Sets, ColmapRealData,
                         ::testing::Values(std::make_tuple("fountain-P11", 11, 14844),
                                           std::make_tuple("templeSparseRing", 16, 1452),
                                           std::make_tuple("dinoSparseRing", 16, 303)));

TEST(ColmapIo, FountainSharesOneCameraWhenWritten) {
  if (!testing::HaveSharedData()) GTEST_SKIP() << "../shared/data not present";
  const Scene scene = ReadScene(SharedData("fountain-P11/sparse"));
  testing::TempDir dir("colmap_fountain");
  WriteColmapModel(scene, dir.path().string(), false, {});
  const std::string cameras = ReadFileToString(dir / "cameras.txt");
  EXPECT_NE(
      cameras.find("# Number of cameras: 1\n1 PINHOLE 3072 2048 2759.48 2764.16 1520.69 1006.81\n"),
      std::string::npos)
      << cameras;
  testing::ExpectScenesNear(scene, ReadColmapModel(dir.path().string(), false, {}), 1e-14);
}

}  // namespace
}  // namespace ms
