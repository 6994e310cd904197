#include "scene/scene_io.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "base/error.h"
#include "base/file_util.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::DataPath;

TEST(SceneIo, FormatNamesRoundTrip) {
  for (SceneFormat f : {SceneFormat::kAuto, SceneFormat::kManisweepH5, SceneFormat::kColmapText,
                        SceneFormat::kColmapBinary, SceneFormat::kNvm, SceneFormat::kBundler,
                        SceneFormat::kOpenMvg, SceneFormat::kStrecha, SceneFormat::kMiddlebury}) {
    EXPECT_EQ(ParseSceneFormat(SceneFormatName(f)), f);
  }
  EXPECT_THROW(ParseSceneFormat("ply"), InputError);
}

TEST(SceneIo, DetectsEveryFormat) {
  EXPECT_EQ(DetectSceneFormat(DataPath("colmap/text")), SceneFormat::kColmapText);
  EXPECT_EQ(DetectSceneFormat(DataPath("colmap/bin")), SceneFormat::kColmapBinary);
  EXPECT_EQ(DetectSceneFormat(DataPath("nvm/two_models.nvm")), SceneFormat::kNvm);
  EXPECT_EQ(DetectSceneFormat(DataPath("bundler/colmap.bundle.out")), SceneFormat::kBundler);
  EXPECT_EQ(DetectSceneFormat(DataPath("openmvg/sfm_data.json")), SceneFormat::kOpenMvg);
  EXPECT_EQ(DetectSceneFormat(DataPath("strecha")), SceneFormat::kStrecha);
  EXPECT_EQ(DetectSceneFormat(DataPath("middlebury/tiny_par.txt")), SceneFormat::kMiddlebury);
  EXPECT_THROW(DetectSceneFormat(DataPath("images")), InputError);
  EXPECT_THROW(DetectSceneFormat(DataPath("no such thing")), InputError);
  testing::TempDir dir("detect");
  // sparse/0/ inside a project folder, and formats recognised by content.
  std::filesystem::create_directories(dir / "project/sparse/0");
  std::filesystem::copy_file(DataPath("colmap/text/cameras.txt"),
                             dir / "project/sparse/0/cameras.txt");
  EXPECT_EQ(DetectSceneFormat(dir / "project"), SceneFormat::kColmapText);
  WriteFileAtomically(dir / "model", [](std::ostream& o) { o << "NVM_V3\n"; });
  EXPECT_EQ(DetectSceneFormat(dir / "model"), SceneFormat::kNvm);
  WriteFileAtomically(dir / "scene.h5", [](std::ostream& o) { o << "x"; });
  EXPECT_EQ(DetectSceneFormat(dir / "scene.h5"), SceneFormat::kManisweepH5);
  try {
    ReadScene(dir / "scene.h5");  // named .h5 but not HDF5 inside
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.h5"), std::string::npos) << e.what();
  }
  EXPECT_EQ(InferOutputFormat(dir / "out.nvm"), SceneFormat::kNvm);
  EXPECT_EQ(InferOutputFormat(dir / "x_par.txt"), SceneFormat::kMiddlebury);
  EXPECT_EQ(InferOutputFormat(dir / "newdir"), SceneFormat::kColmapText);
  EXPECT_EQ(InferOutputFormat(DataPath("colmap/bin")), SceneFormat::kColmapBinary);
}

// The synthetic scene (fx = fy, centred principal points, no distortion) survives every format
// that holds points: cameras to 1e-12 relative, points, colours and visibility exactly.
TEST(SceneIo, RoundTripThroughEveryPointFormat) {
  testing::TempDir dir("roundtrip");
  const Scene scene = testing::MakeSyntheticScene(dir.path().string());
  const std::pair<SceneFormat, std::string> targets[] = {
      {SceneFormat::kNvm, "scene.nvm"},
      {SceneFormat::kColmapText, "text"},
      {SceneFormat::kColmapBinary, "binary"},
      {SceneFormat::kBundler, "bundle.out"},
      {SceneFormat::kBundler, "other.bundle.out"}};
  for (const auto& [format, name] : targets) {
    SCOPED_TRACE(name);
    const std::string path = dir / name;
    WriteScene(scene, path, format);
    EXPECT_EQ(DetectSceneFormat(path), format);
    const Scene back = ReadScene(path);
    testing::ExpectScenesNear(scene, back, 1e-12);
    // Chained: what we read back converts on without change.
    WriteScene(back, path + ".again.nvm", SceneFormat::kNvm);
    testing::ExpectScenesNear(scene, ReadScene(path + ".again.nvm"), 1e-12);
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "list.txt"));
  EXPECT_TRUE(std::filesystem::exists(dir / "other.list.txt"));
}

TEST(SceneIo, LossIsAnErrorUnlessAllowed) {
  testing::TempDir dir("lossy");
  Scene scene = testing::MakeSyntheticScene(dir.path().string());
  scene.views[1].intrinsics.fy += 1;
  scene.views[2].intrinsics.cx += 0.5;
  try {
    WriteScene(scene, dir / "x.out", SceneFormat::kBundler);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "x.out") +
                                         ": Bundler cannot hold fx != fy (written: their mean) "
                                         "(pass --allow-lossy to write it anyway without that)");
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "x.out"));
  SceneWriteOptions lossy;
  lossy.allow_lossy = true;
  WriteScene(scene, dir / "x.out", SceneFormat::kBundler, lossy);
  const Scene back = ReadScene(dir / "x.out");
  EXPECT_EQ(back.views[1].intrinsics.fx, scene.views[1].intrinsics.fx + 0.5);
  EXPECT_EQ(back.views[2].intrinsics.cx, 24.0);
  // COLMAP holds all of it; NVM too only when the views share K (FixedK).
  WriteScene(scene, dir / "c", SceneFormat::kColmapText);
  testing::ExpectScenesNear(scene, ReadScene(dir / "c"), 1e-12);
  EXPECT_THROW(WriteScene(scene, dir / "x.nvm", SceneFormat::kNvm), InputError);
  // Camera-only formats lose the points.
  EXPECT_THROW(WriteScene(scene, dir / "s", SceneFormat::kStrecha), InputError);
}

TEST(SceneIo, MissingImagesForSizes) {
  testing::TempDir dir("missing");
  const Scene scene = testing::MakeSyntheticScene(dir.path().string());
  WriteScene(scene, dir / "m.nvm", SceneFormat::kNvm);
  std::filesystem::remove(dir / "view1.png");
  try {
    ReadScene(dir / "m.nvm");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "m.nvm") + ": image 'view1.png' not found", 0), 0u)
        << e.what();
  }
  // COLMAP stores sizes: a missing image is fine unless required.
  WriteScene(scene, dir / "c", SceneFormat::kColmapBinary);
  EXPECT_EQ(ReadScene(dir / "c").views[1].image_path, "");
  SceneReadOptions options;
  options.require_images = true;
  EXPECT_THROW(ReadScene(dir / "c", options), InputError);
  options = {};
  options.nvm_model_index = -1;
  EXPECT_THROW(options.Check(), InputError);
}

TEST(SceneIo, ImageSizeMismatchIsAnError) {
  testing::TempDir dir("mismatch");
  Scene scene = testing::MakeSyntheticScene(dir.path().string());
  scene.views[0].intrinsics.width += 2;
  scene.views[0].intrinsics.cx += 1;
  WriteScene(scene, dir / "c", SceneFormat::kColmapText);
  try {
    ReadScene(dir / "c");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the model says 42x30 but the image"), std::string::npos)
        << e.what();
  }
  SceneReadOptions options;
  options.read_image_sizes = false;
  EXPECT_NO_THROW(ReadScene(dir / "c", options));
}

}  // namespace
}  // namespace ms
