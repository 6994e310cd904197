// The photo-consistency figure on the analytic pyramid scene (testing/sweep_test_scene.h): the true
// surface is consistent almost everywhere it is seen, a mesh 0.15 off much less, a mesh out of
// every view nowhere; shares are counted over all pixels.
#include "tools/consistency.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "base/error.h"
#include "testing/sweep_test_scene.h"
#include "testing/testing.h"

namespace ms {
namespace {

namespace fs = std::filesystem;

// The pyramid's three cameras as a scene whose images are 16-bit PNG files.
Scene WritePyramidScene(const PyramidScene& pyramid, const fs::path& dir) {
  fs::create_directories(dir);
  Scene scene;
  for (const SweepCamera& camera : pyramid.cameras) {
    View view = camera.view;
    view.image_path = (dir / ("view" + std::to_string(camera.id) + ".png")).string();
    cv::Mat image16;
    camera.image.convertTo(image16, CV_16U, 65535.0);
    cv::imwrite(view.image_path, image16);
    scene.views.push_back(view);
  }
  return scene;
}

TEST(Consistency, TrueSurfaceBeatsAWrongOneAndMissingCounts) {
  const PyramidScene& pyramid = NoisyPyramidScene();
  const Scene scene =
      WritePyramidScene(pyramid, fs::path(::testing::TempDir()) / "ms_consistency_test");
  ConsistencyOptions options;
  options.sweep.gaussian_sigma_px = 4;  // 160 x 120 images
  const ConsistencyReport truth = MeasureConsistency(scene, pyramid.truth, options);
  const ConsistencyReport flat = MeasureConsistency(scene, MakeFlatSquare(0.15, 1.3, 8), options);
  std::printf("true surface:\n%sflat square at 0.15:\n%s", truth.ToTable().c_str(),
              flat.ToTable().c_str());
  ASSERT_EQ(truth.cameras.size(), 3u);
  EXPECT_EQ(truth.total.pixels, 3 * 160 * 120);
  EXPECT_GT(truth.ConsistentShare(), 0.8);
  EXPECT_LT(flat.ConsistentShare(), truth.ConsistentShare() - 0.2);
  // Of the covered pixels the true surface is consistent nearly everywhere.
  EXPECT_GT(static_cast<double>(truth.total.consistent) / truth.total.covered, 0.9);
  // A mesh out of view covers nothing and scores 0 over the same pixels.
  const ConsistencyReport away = MeasureConsistency(scene, MakeFlatSquare(-50, 0.1, 1), options);
  EXPECT_EQ(away.total.pixels, truth.total.pixels);
  EXPECT_EQ(away.total.consistent, 0);
  // Bad options name themselves.
  options.ncc_threshold = 1.5;
  testing::ExpectInputError([&] { MeasureConsistency(scene, pyramid.truth, options); },
                            {"threshold"});
}

// Restricted to the pixels another mesh covers, every count is of those pixels: a mesh measured
// within itself keeps its covered pixels, a smaller mask keeps fewer, and a mask out of view none.
TEST(Consistency, WithinAnotherMeshCountsOnlyItsPixels) {
  const PyramidScene& pyramid = NoisyPyramidScene();
  const Scene scene =
      WritePyramidScene(pyramid, fs::path(::testing::TempDir()) / "ms_consistency_within_test");
  ConsistencyOptions options;
  options.sweep.gaussian_sigma_px = 4;
  const ConsistencyReport all = MeasureConsistency(scene, pyramid.truth, options);
  const Mesh patch = MakeFlatSquare(0.0, 0.4, 4);
  const ConsistencyReport within = MeasureConsistency(scene, pyramid.truth, options, &patch);
  ASSERT_EQ(within.cameras.size(), all.cameras.size());
  for (size_t c = 0; c < all.cameras.size(); ++c) {
    EXPECT_GT(within.cameras[c].pixels, 0) << "camera " << c;
    EXPECT_LT(within.cameras[c].pixels, all.cameras[c].pixels / 2) << "camera " << c;
    EXPECT_LE(within.cameras[c].covered, within.cameras[c].pixels) << "camera " << c;
    EXPECT_LE(within.cameras[c].consistent, all.cameras[c].consistent) << "camera " << c;
  }
  // The truth is consistent on the patch's pixels as it is everywhere it is seen.
  EXPECT_GT(static_cast<double>(within.total.consistent) / within.total.pixels, 0.8);
  // Within itself: its own covered pixels (two rasterizers with the same fill rule).
  const ConsistencyReport itself =
      MeasureConsistency(scene, pyramid.truth, options, &pyramid.truth);
  EXPECT_NEAR(static_cast<double>(itself.total.pixels), static_cast<double>(all.total.covered),
              0.002 * all.total.covered);
  EXPECT_EQ(itself.total.consistent, all.total.consistent);
  const Mesh away = MakeFlatSquare(-50, 0.1, 1);
  EXPECT_EQ(MeasureConsistency(scene, pyramid.truth, options, &away).total.pixels, 0);
}

}  // namespace
}  // namespace ms
