#include "tools/evaluate.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "testing/gl_testing.h"
#include "tools/plot.h"
#include "tools/synth.h"
#include "tools/synth_scenes.h"

namespace ms {
namespace {

class EvaluateTest : public gl::SharedGlContextTest {};

Scene SceneOf(const SynthGeometry& g) {
  Scene scene;
  scene.views = g.views;
  scene.source = "test scene";
  return scene;
}

TEST(CompareDepthMaps, KnownErrors) {
  cv::Mat gt(2, 3, CV_32F, cv::Scalar(2.0f));
  gt.at<float>(1, 2) = 0;  // no ground truth: ignored
  cv::Mat depth = gt.clone();
  depth.at<float>(0, 0) = 2.1f;   // error 0.1
  depth.at<float>(0, 1) = 1.75f;  // error 0.25
  depth.at<float>(0, 2) = 0;      // missing: lowers coverage
  depth.at<float>(1, 2) = 5;      // outside the ground truth: ignored
  const DepthErrorStats s = CompareDepthMaps(depth, gt, 0.06, 10);
  EXPECT_EQ(s.gt_pixels, 5);
  EXPECT_EQ(s.covered_pixels, 4);
  EXPECT_NEAR(s.coverage, 0.8, 1e-12);
  EXPECT_NEAR(s.mae, (0.1 + 0.25) / 4, 1e-6);
  EXPECT_NEAR(s.mre, (0.1 + 0.25) / 2 / 4, 1e-6);
  EXPECT_NEAR(s.rms, std::sqrt((0.01 + 0.0625) / 4), 1e-6);
  ASSERT_EQ(s.cumulative.size(), 10u);
  EXPECT_NEAR(s.cumulative[0], 2 / 5.0, 1e-12);  // the two exact pixels: < 0.06
  EXPECT_NEAR(s.cumulative[1], 3 / 5.0, 1e-12);  // 0.1 < 0.12
  EXPECT_NEAR(s.cumulative[3], 3 / 5.0, 1e-12);  // 0.25 is not < 0.24
  EXPECT_NEAR(s.cumulative[4], 4 / 5.0, 1e-12);  // 0.25 < 0.30
  EXPECT_NEAR(s.cumulative[9], 4 / 5.0, 1e-12);  // never reaches the missing pixel
  // Coverage-complete: the missing pixel counts 10 Sigma, over all 5 ground-truth pixels.
  EXPECT_NEAR(s.missing_penalty, 0.6, 1e-12);
  EXPECT_NEAR(s.mae_all, (0.1 + 0.25 + 0.6) / 5, 1e-6);
}

TEST_F(EvaluateTest, MeshAgainstItselfHasZeroErrorAndFullCoverage) {
  const SynthGeometry g = MakePyramidScene(false, {4, 160, 120, 1});
  const Scene scene = SceneOf(g);
  EvaluateOptions options;
  options.all_views = true;
  const Evaluation e = EvaluateMeshes(*context_, {{"gt", &g.mesh}}, g.mesh, scene, options);
  ASSERT_EQ(e.meshes.size(), 1u);
  const DepthErrorStats& s = e.meshes[0].total;
  EXPECT_GT(s.gt_pixels, 4 * 160 * 120 / 4);
  EXPECT_EQ(s.covered_pixels, s.gt_pixels);
  EXPECT_EQ(s.mae, 0);
  EXPECT_EQ(s.mae_all, 0);
  EXPECT_EQ(s.rms, 0);
  EXPECT_EQ(s.coverage, 1);
  for (double c : s.cumulative) EXPECT_EQ(c, 1);
  EXPECT_EQ(e.meshes[0].views.size(), 4u);
}

TEST_F(EvaluateTest, PlaneShiftedAlongTheViewingDirectionGivesThatError) {
  const Intrinsics k{160, 120, 150, 150, 80, 60};
  const View view = LookAt({0.3, -0.2, 5}, {0.3, -0.2, 0}, Eigen::Vector3d::UnitY(), k);
  Mesh plane;
  plane.vertices = {{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}};
  plane.faces = {{0, 1, 2}, {0, 2, 3}};
  const double shift = 0.137;
  Mesh shifted = plane;
  for (Eigen::Vector3d& v : shifted.vertices) v += shift * view.Axis();  // away from the camera
  Scene scene;
  scene.views = {view};
  EvaluateOptions options;
  options.sigma = 0.06;
  const Evaluation e = EvaluateMeshes(*context_, {{"shifted", &shifted}}, plane, scene, options);
  const DepthErrorStats& s = e.meshes[0].total;
  EXPECT_EQ(s.gt_pixels, 160 * 120);
  EXPECT_NEAR(s.mae, shift, 1e-5);
  EXPECT_NEAR(s.rms, shift, 1e-5);
  EXPECT_NEAR(s.mre, shift / 5, 1e-6);
  EXPECT_EQ(s.cumulative[1], 0);  // 0.137 > 2 * 0.06
  EXPECT_EQ(s.cumulative[2], 1);  // 0.137 < 3 * 0.06
}

TEST_F(EvaluateTest, MeshScaledAboutTheCameraCentreScalesEveryDepth) {
  // A homothety centred on the camera keeps every pixel ray: depths scale exactly, so
  // MRE = |s - 1| also on a non-planar surface.
  const SynthGeometry g = MakePyramidScene(true, {3, 200, 150, 1});
  const View& view = g.views[0];
  const double s = 1.04;
  Mesh scaled = g.mesh;
  for (Eigen::Vector3d& v : scaled.vertices) v = view.Center() + s * (v - view.Center());
  const Evaluation e = EvaluateMeshes(*context_, {{"scaled", &scaled}}, g.mesh, SceneOf(g), {});
  EXPECT_NEAR(e.meshes[0].total.mre, s - 1, 2e-5);
  EXPECT_GT(e.meshes[0].total.coverage, 0.99);
}

TEST_F(EvaluateTest, FlatBaseSquareAgainstThePyramidsIsOnTheOrderOfTheirHeight) {
  // The paper's "w/o mesh sweeping" row: MAE 0.108 m (down) and 0.135 m (up) from the first camera.
  for (bool up : {false, true}) {
    const SynthGeometry g = MakePyramidScene(up, {16, 800, 600, 1});
    const Mesh base = PyramidBaseSquare();
    for (DepthMeasure measure : {DepthMeasure::kCameraZ, DepthMeasure::kRange}) {
      EvaluateOptions options;
      options.sigma = 0.06;
      options.measure = measure;
      const Evaluation e =
          EvaluateMeshes(*context_, {{"base", &base}}, g.mesh, SceneOf(g), options);
      const DepthErrorStats& s = e.meshes[0].total;
      std::fputs(FormatEvaluationTable(e).c_str(), stdout);
      std::printf(
          "pyramid-%s, base square from view 0 (%s): MAE %.4f MRE %.4f RMS %.4f "
          "coverage %.3f, <1..3 Sigma %.2f %.2f %.2f (median depth %.3f)\n",
          up ? "up" : "down", DepthMeasureName(measure).c_str(), s.mae, s.mre, s.rms, s.coverage,
          s.cumulative[0], s.cumulative[1], s.cumulative[2], e.median_gt_depth);
      EXPECT_GT(s.mae, 0.07);
      EXPECT_LT(s.mae, 0.16);
      EXPECT_GT(s.mre, up ? 0.08 : 0.05);  // paper: 0.114 (up), 0.072 (down)
      EXPECT_LT(s.mre, up ? 0.14 : 0.09);
      EXPECT_GT(s.coverage, 0.99);
    }
  }
}

TEST_F(EvaluateTest, DefaultSigmaFollowsTheMedianDepth) {
  const SynthGeometry g = MakePyramidScene(false, {2, 160, 120, 1});
  const Evaluation e = EvaluateMeshes(*context_, {{"gt", &g.mesh}}, g.mesh, SceneOf(g), {});
  EXPECT_GT(e.median_gt_depth, 1.2);
  EXPECT_NEAR(e.sigma, e.median_gt_depth / kSigmaDepthRatio, 1e-12);
  EXPECT_THAT(e.sigma_rule, ::testing::HasSubstr("median"));
  EXPECT_NEAR(e.sigma, 0.06, 0.01);  // the paper's Sigma at its scale
}

TEST(RangeFromDepth, ScalesByTheRayLength) {
  const Intrinsics k{4, 2, 2, 1, 2, 1};
  const cv::Mat range = RangeFromDepth(cv::Mat(2, 4, CV_32F, cv::Scalar(3.0f)), k);
  // Pixel (3, 1): centre (3.5, 1.5) -> ray (0.75, 0.5, 1).
  EXPECT_NEAR(range.at<float>(1, 3), 3 * std::sqrt(0.75 * 0.75 + 0.25 + 1), 1e-5);
  EXPECT_EQ(RangeFromDepth(cv::Mat::zeros(2, 4, CV_32F), k).at<float>(0, 0), 0);
}

TEST_F(EvaluateTest, BadViewsAndEmptyGroundTruthAreInputErrors) {
  const SynthGeometry g = MakePyramidScene(false, {2, 160, 120, 1});
  EvaluateOptions options;
  options.views = {5};
  EXPECT_THROW(EvaluateMeshes(*context_, {{"gt", &g.mesh}}, g.mesh, SceneOf(g), options),
               InputError);
  Mesh far_away = g.mesh;
  for (Eigen::Vector3d& v : far_away.vertices) v.z() += 100;  // behind every camera
  EXPECT_THROW(EvaluateMeshes(*context_, {{"gt", &g.mesh}}, far_away, SceneOf(g), {}), InputError);
}

TEST_F(EvaluateTest, TableAndJsonCarryTheNumbers) {
  const SynthGeometry g = MakePyramidScene(true, {2, 160, 120, 1});
  const Mesh base = PyramidBaseSquare();
  EvaluateOptions options;
  options.sigma = 0.06;
  options.all_views = true;
  const Evaluation e = EvaluateMeshes(*context_, {{"base.ply", &base}, {"gt.ply", &g.mesh}}, g.mesh,
                                      SceneOf(g), options);
  const std::string table = FormatEvaluationTable(e);
  EXPECT_THAT(table, ::testing::HasSubstr("base.ply"));
  EXPECT_THAT(table, ::testing::HasSubstr("MAE"));
  EXPECT_THAT(table, ::testing::HasSubstr("<10S"));
  EXPECT_THAT(table, ::testing::HasSubstr(fmt::format("{:.4f}", e.meshes[0].total.mae)));
  const nlohmann::json json = EvaluationToJson(e);
  EXPECT_DOUBLE_EQ(json["meshes"][0]["total"]["mae"].get<double>(), e.meshes[0].total.mae);
  EXPECT_EQ(json["meshes"][1]["total"]["mae"].get<double>(), 0.0);
  EXPECT_EQ(json["meshes"][0]["views"].size(), 2u);
  EXPECT_EQ(json["meshes"][0]["total"]["cumulative"].size(), 10u);
  EXPECT_EQ(json["sigma"].get<double>(), 0.06);
}

TEST_F(EvaluateTest, WritesJsonAndFigures) {
  const SynthGeometry g = MakePyramidScene(false, {3, 320, 240, 1});
  const Mesh base = PyramidBaseSquare();
  EvaluateOptions options;
  options.sigma = 0.06;
  const Evaluation e = EvaluateMeshes(
      *context_, {{"base square", &base}, {"ground truth", &g.mesh}}, g.mesh, SceneOf(g), options);
  const std::string dir = ::testing::TempDir() + "/evaluate_files";
  EvaluationFiles files;
  files.json = dir + "/eval.json";
  files.error_image = dir + "/errors.png";
  files.plot = dir + "/cumulative.png";
  files.ground_truth_name = "gt.ply";
  WriteEvaluationFiles(e, files);
  const nlohmann::json json = nlohmann::json::parse(ReadFileToString(files.json));
  EXPECT_EQ(json["ground_truth"], "gt.ply");
  EXPECT_DOUBLE_EQ(json["meshes"][0]["total"]["mae"].get<double>(), e.meshes[0].total.mae);
  const cv::Mat errors = cv::imread(files.error_image), plot = cv::imread(files.plot);
  ASSERT_FALSE(errors.empty());
  ASSERT_FALSE(plot.empty());
  EXPECT_GT(errors.cols, 2 * 320);  // two panels and a colour bar
  EXPECT_EQ(plot.size(), cv::Size(900, 600));
}

TEST(Plot, ErrorImageColoursAndKey) {
  cv::Mat gt(2, 2, CV_32F, cv::Scalar(1.0f)), depth(2, 2, CV_32F, cv::Scalar(1.0f));
  gt.at<float>(0, 1) = 0;     // no ground truth -> black
  depth.at<float>(1, 0) = 0;  // missing -> white
  depth.at<float>(1, 1) = 2;  // error 1 = max -> red
  const cv::Mat image = ErrorImage(depth, gt, 1.0);
  ASSERT_EQ(image.type(), CV_8UC3);
  EXPECT_EQ(image.at<cv::Vec3b>(0, 1), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(image.at<cv::Vec3b>(1, 0), cv::Vec3b(255, 255, 255));
  const cv::Vec3b zero = image.at<cv::Vec3b>(0, 0), max = image.at<cv::Vec3b>(1, 1);
  EXPECT_GT(zero[0], zero[2]);  // blue for no error
  EXPECT_GT(max[2], max[0]);    // red for the largest
  const cv::Mat figure = ErrorFigure({{"a", depth}, {"b", gt}}, gt, 1.0, 100);
  EXPECT_GT(figure.cols, 2 * 2);
  EXPECT_EQ(figure.type(), CV_8UC3);
}

TEST(Plot, CumulativePlotDrawsCurvesInTheirColours) {
  const cv::Mat plot =
      CumulativePlot({{"initial", {0.1, 0.2, 0.4, 0.6, 0.7, 0.8, 0.85, 0.9, 0.92, 0.95}},
                      {"final", {0.5, 0.8, 0.9, 0.95, 1, 1, 1, 1, 1, 1}}},
                     0.06, "test", cv::Size(600, 400));
  ASSERT_EQ(plot.size(), cv::Size(600, 400));
  // Both palette colours appear (first two: BGR (200,80,30) and (30,30,200)).
  cv::Mat first, second;
  cv::inRange(plot, cv::Scalar(190, 70, 20), cv::Scalar(210, 90, 40), first);
  cv::inRange(plot, cv::Scalar(20, 20, 190), cv::Scalar(40, 40, 210), second);
  EXPECT_GT(cv::countNonZero(first), 200);
  EXPECT_GT(cv::countNonZero(second), 200);
}

}  // namespace
}  // namespace ms
