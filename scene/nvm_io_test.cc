#include "scene/nvm_io.h"

#include <gtest/gtest.h>

#include "base/error.h"
#include "base/file_util.h"
#include "scene/format_util.h"
#include "scene/scene_io.h"
#include "testing/scene_testing.h"

namespace ms {
namespace {

using testing::DataPath;

// Largest distance between an observation and the projection of its point.
double MaxReprojectionError(const Scene& scene) {
  double worst = 0;
  for (const ScenePoint& p : scene.points) {
    for (const Observation& o : p.observations) {
      Eigen::Vector2d px;
      EXPECT_TRUE(scene.views[o.view].Project(p.position, &px));
      worst = std::max(worst, (px - Eigen::Vector2d(o.x, o.y)).norm());
    }
  }
  return worst;
}

TEST(NvmIo, FirstModelOfVisualSfmFile) {
  const Scene scene = ReadScene(DataPath("nvm/two_models.nvm"));
  ASSERT_EQ(scene.views.size(), 3u);
  const View& a = scene.views[0];
  EXPECT_EQ(a.name, "a.png");
  EXPECT_EQ(a.intrinsics.width, 64);  // from tests/data/images/a.png
  EXPECT_EQ(a.intrinsics.fx, 50.0);
  EXPECT_EQ(a.intrinsics.fy, 50.0);
  EXPECT_EQ(a.intrinsics.cx, 32.0);
  EXPECT_EQ(a.intrinsics.cy, 24.0);
  EXPECT_FALSE(a.intrinsics.HasDistortion());
  EXPECT_EQ(a.R, RotationFromQuaternion(0.46329759436098156, 0.5341866144516608, 0.5341866144516609,
                                        -0.46329759436098156));
  EXPECT_LT((a.Center() - Eigen::Vector3d(3.5, 0, 0.5)).norm(), 1e-14);
  const View& c = scene.views[2];
  EXPECT_EQ(c.intrinsics.width, 80);
  EXPECT_EQ(c.intrinsics.cx, 40.0);
  EXPECT_TRUE(c.intrinsics.HasDistortion());  // k = -0.07 converted
  ASSERT_EQ(scene.points.size(), 5u);
  EXPECT_EQ(scene.points[0].position, Eigen::Vector3d(0.3, -0.2, 0.1));
  EXPECT_EQ(scene.points[0].color, (std::array<uint8_t, 3>{255, 0, 10}));
  EXPECT_EQ(scene.points[0].observations.size(), 3u);
  // Measurements were made with VisualSFM's own radial model: our converted cameras reproject
  // them to within the fit's error.
  EXPECT_LT(MaxReprojectionError(scene), 0.01);
}

TEST(NvmIo, ChoosesTheModel) {
  SceneReadOptions options;
  options.nvm_model_index = 1;
  const Scene second = ReadScene(DataPath("nvm/two_models.nvm"), options);
  ASSERT_EQ(second.views.size(), 2u);
  EXPECT_EQ(second.views[0].name, "b.png");
  EXPECT_EQ(second.views[1].intrinsics.fx, 61.0);
  EXPECT_EQ(second.points.size(), 2u);
  EXPECT_LT(MaxReprojectionError(second), 1e-4);
  options.nvm_model_index = 2;
  try {
    ReadScene(DataPath("nvm/two_models.nvm"), options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("model 2 requested but the file holds 2 model(s)"),
              std::string::npos)
        << e.what();
  }
}

TEST(NvmIo, R9tAndFixedK) {
  const Scene r9t = ReadScene(DataPath("nvm/r9t.nvm"));
  ASSERT_EQ(r9t.views.size(), 2u);
  EXPECT_EQ(r9t.views[1].name, "d.png");
  EXPECT_LT(MaxReprojectionError(r9t), 1e-4);
  const Scene fixed = ReadScene(DataPath("nvm/fixedk.nvm"));
  ASSERT_EQ(fixed.views.size(), 2u);
  const Intrinsics& k = fixed.views[1].intrinsics;
  EXPECT_EQ(k.fx, 52.0);
  EXPECT_EQ(k.fy, 51.0);
  EXPECT_EQ(k.cx, 31.5);
  EXPECT_EQ(k.cy, 24.5);
  EXPECT_LT(MaxReprojectionError(fixed), 1e-4);
}

TEST(NvmIo, VisualSfmDistortionFit) {
  // (k, largest error in normalised units over radius 0.9): the fit is a 3-term polynomial, so
  // strong distortion leaves more; 1e-5 is 0.001 px at f = 100.
  for (const auto& [k, tolerance] :
       {std::pair{-0.2, 1.5e-3}, {-0.07, 3e-5}, {0.05, 1e-5}, {0.3, 1.5e-3}}) {
    double k1, k2, k3;
    const double error = format::FitOpenCvToVisualSfm(k, 0.9, "test", &k1, &k2, &k3);
    EXPECT_LT(error, tolerance) << k;
    RecordProperty("fit_error_k" + std::to_string(k), std::to_string(error));
    // First-order agreement: OpenCV's k1 is about -k.
    EXPECT_NEAR(k1, -k, 0.35 * std::abs(k));
    // Spot check with the inverse map directly.
    const double rd = 0.6, ru = rd * (1 + k * rd * rd);
    const double ru2 = ru * ru;
    EXPECT_NEAR(ru * (1 + ru2 * (k1 + ru2 * (k2 + ru2 * k3))), rd, tolerance);
  }
  double k1, k2, k3;
  EXPECT_EQ(format::FitOpenCvToVisualSfm(0, 0.9, "test", &k1, &k2, &k3), 0.0);
  EXPECT_EQ(k1, 0.0);
  EXPECT_THROW(format::FitOpenCvToVisualSfm(-1.0, 0.9, "test", &k1, &k2, &k3), InputError);
  EXPECT_NEAR(format::FitVisualSfmToOpenCv(-0.05, 0, 0, 0.5), 0.05, 0.01);
}

TEST(NvmIo, SharedOffCentreIntrinsicsUseFixedK) {
  if (!testing::HaveSharedData()) GTEST_SKIP() << "../shared/data not present";
  const Scene temple = ReadScene(testing::SharedData("templeSparseRing/sparse"));
  testing::TempDir dir("nvm_fixedk");
  const std::string path = dir / "temple.nvm";
  WriteNvm(temple, path, {});
  EXPECT_EQ(ReadFileToString(path).rfind("NVM_V3 FixedK 1520.4 302.32 1525.9 246.87 0\n", 0), 0u);
  SceneReadOptions options;
  options.image_dir = testing::SharedData("templeSparseRing");
  testing::ExpectScenesNear(temple, ReadScene(path, options), 1e-12);
}

TEST(NvmIo, MissingImageIsNamed) {
  const std::string nvm = "NVM_V3\n\n1\nnowhere.png 50 1 0 0 0 0 0 0 0 0\n0\n";
  try {
    ParseNvm("x.nvm", nvm, 0, [](const std::string& name) -> ImageSize {
      throw InputError("x.nvm: image '" + name + "' not found");
    });
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "x.nvm: image 'nowhere.png' not found");
  }
}

}  // namespace
}  // namespace ms
