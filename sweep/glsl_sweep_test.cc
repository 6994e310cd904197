// The GLSL sweep kernel against the C++ reference (docs/design/sweep.md "The GLSL kernel"): per
// stage (swept mesh seen from C, shadow maps, reprojection, NCC) and end to end, for both blur
// variants, on llvmpipe in CI (on a GPU where there is one). Tolerances are those of the docs.
#include "sweep/glsl_sweep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <utility>

#include "base/error.h"
#include "sweep/reference_sweep.h"
#include "sweep/sweep_kernel_factory.h"
#include "testing/gl_testing.h"
#include "testing/sweep_parity_testing.h"
#include "testing/sweep_test_scene.h"
#include "testing/testing.h"

namespace ms {
namespace {

// One context and a kernel per blur variant for the whole suite (contexts are slow to make).
class GlslSweepTest : public gl::SharedGlContextTest {
 protected:
  static void SetUpTestSuite() {
    SharedGlContextTest::SetUpTestSuite();
    GlslSweepKernelOptions loops;
    loops.blur = GlslBlurVariant::kLoops;
    loops_ = new GlslSweepKernel(*context_, loops);
    GlslSweepKernelOptions unrolled;
    unrolled.blur = GlslBlurVariant::kUnrolled;
    unrolled_ = new GlslSweepKernel(*context_, unrolled);
  }
  static void TearDownTestSuite() {
    delete loops_;
    delete unrolled_;
    SharedGlContextTest::TearDownTestSuite();
  }
  static std::vector<GlslSweepKernel*> Kernels() { return {loops_, unrolled_}; }
  static std::string Label(const GlslSweepKernel* k) {
    return k->blur_variant() == GlslBlurVariant::kLoops ? "loops" : "unrolled";
  }
  static GlslSweepKernel* loops_;
  static GlslSweepKernel* unrolled_;
};
GlslSweepKernel* GlslSweepTest::loops_ = nullptr;
GlslSweepKernel* GlslSweepTest::unrolled_ = nullptr;

// The reference's steps for offset k (docs/design/sweep.md), as ReferenceSweepKernel runs them.
struct ReferenceStages {
  PreparedSweep prep;
  std::unique_ptr<SoftwareRasterizer> camera;
  std::vector<SoftwareRasterizer> shadows;
  std::vector<cv::Mat> reprojected, mask, ncc;
};

ReferenceStages RunReferenceStages(const SweepJob& job, int k) {
  ReferenceStages s;
  s.prep = PrepareSweep(job);
  const auto soup =
      SweepFacets(job.mesh, FaceNormals(job.mesh), s.prep.camera.view.Center(), s.prep.alpha * k);
  s.camera = std::make_unique<SoftwareRasterizer>(s.prep.camera.view, s.prep.near, true);
  RenderSoup(soup, s.camera.get());
  for (const SweepCamera& n : s.prep.neighbours) {
    s.shadows.emplace_back(n.view, s.prep.near, false);
    RenderSoup(soup, &s.shadows.back());
    cv::Mat reprojected, mask, ncc;
    ReprojectNeighbour(*s.camera, n.view, n.image, s.shadows.back(),
                       job.options.occlusion_tolerance, &reprojected, &mask);
    WeightedNcc(s.prep.camera.image, reprojected, mask, s.prep.window,
                job.options.min_texture_variance, job.options.min_window_weight, &ncc);
    s.reprojected.push_back(reprojected);
    s.mask.push_back(mask);
    s.ncc.push_back(ncc);
  }
  return s;
}

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(q * (values.size() - 1))];
}

// Per-pixel comparison of two NCC maps: how often exactly one is defined, and the differences
// where both are.
struct NccDiff {
  int64_t both = 0, only_one = 0;
  std::vector<double> diffs;
};

NccDiff CompareNcc(const cv::Mat& a, const cv::Mat& b) {
  NccDiff d;
  for (int r = 0; r < a.rows; ++r) {
    for (int c = 0; c < a.cols; ++c) {
      const float x = a.at<float>(r, c), y = b.at<float>(r, c);
      if (std::isnan(x) != std::isnan(y)) ++d.only_one;
      if (std::isnan(x) || std::isnan(y)) continue;
      ++d.both;
      d.diffs.push_back(std::abs(x - y));
    }
  }
  return d;
}

// ---- Per stage ----

// Neighbour j's stages of one GLSL kernel's capture against the reference: its shadow map, the
// reprojection through it and the NCC.
void ExpectNeighbourStagesMatch(const ReferenceStages& ref, const GlslSweepCapture& capture,
                                const SweepJob& job, int j, const std::string& label) {
  const int width = ref.prep.camera.view.intrinsics.width;
  const int height = ref.prep.camera.view.intrinsics.height;
  const int64_t pixels = int64_t{width} * height;
  // Shadow maps.
  const SoftwareRasterizer& shadow = ref.shadows[j];
  int64_t shadow_differs = 0;
  double worst_depth = 0;
  for (int r = 0; r < shadow.height(); ++r) {
    for (int c = 0; c < shadow.width(); ++c) {
      const double a = shadow.depth()[shadow.Index(c, r)];
      const double b = capture.shadow[j].at<float>(r, c);
      if (std::isinf(a) != std::isinf(b)) ++shadow_differs;
      if (std::isinf(a) || std::isinf(b)) continue;
      worst_depth = std::max(worst_depth, std::abs(a - b) / a);
    }
  }
  EXPECT_LE(shadow_differs, pixels / 1000);
  EXPECT_LT(worst_depth, 1e-5);

  // Reprojection: validity and values (where both kernels see the same face).
  int64_t mask_differs = 0, valid = 0, occluded = 0;
  double worst_value = 0;
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const bool a = ref.mask[j].at<uint8_t>(r, c) != 0;
      const bool b = capture.mask[j].at<uint8_t>(r, c) != 0;
      if (a != b) ++mask_differs;
      const size_t i = ref.camera->Index(c, r);
      if (ref.camera->face()[i] >= 0 && !a) ++occluded;
      if (!a || !b || ref.camera->face()[i] != capture.face.at<int32_t>(r, c)) continue;
      ++valid;
      worst_value = std::max<double>(worst_value, std::abs(ref.reprojected[j].at<float>(r, c) -
                                                           capture.reprojected[j].at<float>(r, c)));
    }
  }
  std::printf(
      "[%s] neighbour %d: shadow differs at %lld (worst depth %.1e rel.); mask "
      "differs at %lld of %lld valid (%lld invalid), worst value %.1e\n",
      label.c_str(), j, static_cast<long long>(shadow_differs), worst_depth,
      static_cast<long long>(mask_differs), static_cast<long long>(valid),
      static_cast<long long>(occluded), worst_value);
  EXPECT_GT(valid, pixels / 2);
  EXPECT_GT(occluded, 100);  // the occluder and the image borders invalidate some
  EXPECT_LE(mask_differs, pixels / 500);
  EXPECT_LT(worst_value, 1e-4);

  // NCC on the same input as the GPU's (isolates the blur and the formula): equal up to
  // float summation order.
  cv::Mat same_input;
  WeightedNcc(ref.prep.camera.image, capture.reprojected[j], capture.mask[j], ref.prep.window,
              job.options.min_texture_variance, job.options.min_window_weight, &same_input);
  const NccDiff isolated = CompareNcc(same_input, capture.ncc[j]);
  // NCC end to end (each kernel's own reprojection): silhouettes may differ.
  const NccDiff end_to_end = CompareNcc(ref.ncc[j], capture.ncc[j]);
  std::printf(
      "[%s] neighbour %d NCC: same input %lld defined, %lld differ in definedness, "
      "|diff| p99.9 %.1e max %.1e; end to end %lld / %lld, p99 %.1e max %.1e\n",
      label.c_str(), j, static_cast<long long>(isolated.both),
      static_cast<long long>(isolated.only_one), Quantile(isolated.diffs, 0.999),
      Quantile(isolated.diffs, 1.0), static_cast<long long>(end_to_end.both),
      static_cast<long long>(end_to_end.only_one), Quantile(end_to_end.diffs, 0.99),
      Quantile(end_to_end.diffs, 1.0));
  EXPECT_GT(isolated.both, pixels / 2);
  EXPECT_LE(isolated.only_one, pixels / 5000);
  EXPECT_LT(Quantile(isolated.diffs, 0.999), 1e-4);
  EXPECT_LT(Quantile(isolated.diffs, 1.0), 1e-3);
  // The GPU's world positions are float (~2e-7 x depth): reprojected values differ by
  // ~1e-5, which moves the NCC of windows with little variance by up to ~1e-3.
  EXPECT_LE(end_to_end.only_one, pixels / 200);
  EXPECT_LT(Quantile(end_to_end.diffs, 0.9), 1e-4);
  EXPECT_LT(Quantile(end_to_end.diffs, 0.99), 5e-4);
  EXPECT_LT(Quantile(end_to_end.diffs, 1.0), 3e-3);
}

TEST_F(GlslSweepTest, StagesMatchTheReference) {
  const PyramidScene& scene = NoisyPyramidScene();
  SweepJob job = MakeSmallSweepJob(scene, TruthWithOccluder(scene));
  job.options.alpha = 0.02;
  const int k = 3;  // a swept mesh, not the input one
  const ReferenceStages ref = RunReferenceStages(job, k);
  const View& view = ref.prep.camera.view;
  const int width = view.intrinsics.width, height = view.intrinsics.height;
  const int64_t pixels = int64_t{width} * height;

  for (GlslSweepKernel* kernel : Kernels()) {
    SCOPED_TRACE(Label(kernel));
    GlslSweepCapture capture;
    capture.offset = k;
    kernel->Run(job, &capture);
    ASSERT_EQ(capture.world.size(), cv::Size(width, height));
    ASSERT_EQ(capture.shadow.size(), 2u);

    // Swept mesh seen from C: coverage, face, world position and depth.
    int64_t coverage_differs = 0, face_differs = 0, both = 0;
    double worst_position = 0, worst_c_depth = 0;
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) {
        const size_t i = ref.camera->Index(c, r);
        const int32_t ref_face = ref.camera->face()[i];
        const int32_t gl_face = capture.face.at<int32_t>(r, c);
        if ((ref_face >= 0) != (gl_face >= 0)) ++coverage_differs;
        if (ref_face < 0 || gl_face < 0) continue;
        ++both;
        if (ref_face != gl_face) {
          ++face_differs;
          continue;
        }
        const cv::Vec3f w = capture.world.at<cv::Vec3f>(r, c);
        const Eigen::Vector3d gl_world(w[0], w[1], w[2]);
        const double z = ref.camera->depth()[i];
        worst_position = std::max(worst_position, (gl_world - ref.camera->world()[i]).norm() / z);
        worst_c_depth = std::max(worst_c_depth, std::abs(capture.depth.at<float>(r, c) - z) / z);
      }
    }
    std::printf(
        "[%s] C view: %lld covered, coverage differs at %lld, face at %lld; worst "
        "position error %.2e x depth, depth %.2e relative\n",
        Label(kernel).c_str(), static_cast<long long>(both),
        static_cast<long long>(coverage_differs), static_cast<long long>(face_differs),
        worst_position, worst_c_depth);
    EXPECT_GT(both, pixels * 9 / 10);
    EXPECT_LE(coverage_differs, pixels / 1000);  // pixel centres within float error of an edge
    EXPECT_LE(face_differs, both / 200);
    EXPECT_LT(worst_position, 1e-5);
    EXPECT_LT(worst_c_depth, 1e-5);

    for (int j = 0; j < 2; ++j) ExpectNeighbourStagesMatch(ref, capture, job, j, Label(kernel));
  }
}

// ---- End to end ----

// Tile winners are compared by ExpectSameWinners (testing/sweep_parity_testing.h). With the paper's
// rule, and where winners must move (the default) below.
TEST_F(GlslSweepTest, PyramidFromAFlatSquareLikeTheReference) {
  const PyramidScene& scene = NoisyPyramidScene();
  SweepJob job = MakeSmallSweepJob(scene, MakeFlatSquare(0.15, 1.3, 8));
  job.options.winners_must_move = false;
  const SweepResult ref = ReferenceSweepKernel().Run(job);
  job.options.winners_must_move = true;
  const SweepResult moving = ReferenceSweepKernel().Run(job);
  job.options.winners_must_move = false;
  for (GlslSweepKernel* kernel : Kernels()) {
    SCOPED_TRACE(Label(kernel));
    const SweepResult gl = kernel->Run(job);
    ExpectSameWinners(ref, gl, ref.stats.median_depth, Label(kernel));
    job.options.winners_must_move = true;
    const SweepResult gl_moving = kernel->Run(job);
    job.options.winners_must_move = false;
    ExpectSameWinners(moving, gl_moving, ref.stats.median_depth,
                      Label(kernel) + ", winners must move");
    // Both sweep k = 0 and count its hypotheses.
    EXPECT_EQ(gl.stats.valid_hypotheses, gl_moving.stats.valid_hypotheses);
    EXPECT_EQ(gl.stats.covered_pixels, gl_moving.stats.covered_pixels);
    std::vector<double> d;
    for (const SweepPoint& p : gl.points) {
      d.push_back(scene.Distance(p.position));
      EXPECT_GT(p.ncc, 0.98f);
      const Eigen::Vector3d ray = job.camera.view.PixelRay(p.pixel.cast<double>());
      EXPECT_LT((ray - (p.position - job.camera.view.Center()).normalized()).norm(), 1e-5);
    }
    ASSERT_GT(d.size(), 40u);
    std::printf("[%s] distance to the truth: median %.4f, p90 %.4f\n  %s\n", Label(kernel).c_str(),
                Quantile(d, 0.5), Quantile(d, 0.9), gl.stats.Summary().c_str());
    EXPECT_LT(Quantile(d, 0.5), 0.01);
    EXPECT_LT(Quantile(d, 0.9), 0.03);
  }
}

TEST_F(GlslSweepTest, TrueMeshWithOcclusionAndDefaultWindow) {
  const PyramidScene& scene = NoisyPyramidScene();
  SweepJob job = MakeSmallSweepJob(scene, TruthWithOccluder(scene));
  job.options.num_offsets = 5;
  job.options.alpha = 0.03;
  job.options.gaussian_sigma_px = 8;      // the default window (radius 24)
  job.options.winners_must_move = false;  // on the true mesh most winners are at k = 0
  // Two matching neighbours where both see the pixel, the strict rule (the default) and the
  // paper's (any one).
  for (const auto& [required, strict] :
       {std::pair{2, false}, std::pair{2, true}, std::pair{1, false}}) {
    job.options.min_matching_neighbours = required;
    job.options.strict_support = strict;
    const SweepResult ref = ReferenceSweepKernel().Run(job);
    ASSERT_GT(ref.points.size(), 30u);
    for (GlslSweepKernel* kernel : Kernels()) {
      SCOPED_TRACE(Label(kernel) + ", " + std::to_string(required) + " matching" +
                   (strict ? ", strict" : ""));
      ExpectSameWinners(ref, kernel->Run(job), ref.stats.median_depth, Label(kernel));
    }
  }
}

// (The loops variant where the variant does not matter: its shaders compile much faster.)
TEST_F(GlslSweepTest, BatchingAndVariantsGiveTheSameResult) {
  const SweepJob job = MakeSmallSweepJob(NoisyPyramidScene(), MakeFlatSquare(0.12, 1.3, 4));
  const SweepResult whole = loops_->Run(job);
  GlslSweepKernelOptions one_at_a_time;
  one_at_a_time.blur = GlslBlurVariant::kLoops;
  one_at_a_time.max_batch_offsets = 1;
  one_at_a_time.time_stages = false;
  GlslSweepKernel batched(*context_, one_at_a_time);
  const SweepResult single = batched.Run(job);
  ASSERT_EQ(whole.points.size(), single.points.size());
  for (size_t i = 0; i < whole.points.size(); ++i) {
    EXPECT_EQ(whole.points[i].position, single.points[i].position);
    EXPECT_EQ(whole.points[i].ncc, single.points[i].ncc);
    EXPECT_EQ(whole.points[i].pixel, single.points[i].pixel);
    EXPECT_EQ(whole.points[i].cameras, single.points[i].cameras);
  }
  EXPECT_EQ(whole.stats.valid_hypotheses, single.stats.valid_hypotheses);
  EXPECT_EQ(whole.stats.covered_pixels, single.stats.covered_pixels);
  EXPECT_EQ(single.stats.raster_s, 0);  // no stage timing asked for
  // Outputs per invocation and the unrolled variant: the same winners, NCC up to float
  // summation order.
  GlslSweepKernelOptions blocks;
  blocks.blur = GlslBlurVariant::kLoops;
  blocks.blur_block = 5;
  GlslSweepKernel blocked(*context_, blocks);
  for (const SweepResult& other : {blocked.Run(job), unrolled_->Run(job)}) {
    ASSERT_EQ(other.points.size(), whole.points.size());
    for (size_t i = 0; i < other.points.size(); ++i) {
      EXPECT_EQ(other.points[i].pixel, whole.points[i].pixel);
      EXPECT_EQ(other.points[i].offset, whole.points[i].offset);
      EXPECT_NEAR(other.points[i].ncc, whole.points[i].ncc, 1e-5);
    }
  }
}

TEST_F(GlslSweepTest, ManyNeighboursAndPyramidLevels) {
  // 34 neighbours: several reprojection dispatches (at most 7 neighbours each) and two words
  // of matched-neighbour bits; at pyramid level 1.
  PyramidSceneOptions options;
  options.width = 96;
  options.height = 72;
  options.supersample = 1;
  const PyramidScene scene = MakePyramidScene(options);
  SweepJob job = MakeSmallSweepJob(scene, scene.truth);
  job.neighbours.clear();
  for (int i = 0; i < 34; ++i) {
    SweepCamera n = scene.cameras[1 + i % 2];
    n.id = 10 + i;
    job.neighbours.push_back(n);
  }
  job.options.num_offsets = 3;
  job.options.alpha = 0.02;
  job.options.tile_size_px = 8;
  job.options.gaussian_sigma_px = 2;
  job.options.max_image_dimension = 60;
  // Its 48 x 36 images are texture at the pixel scale, which reads as 19 grey levels of noise:
  // kept unsmoothed, as the parity bounds were set (smoothing: sweep_kernel_test).
  job.options.image_noise_target = 0;
  const SweepResult ref = ReferenceSweepKernel().Run(job);
  EXPECT_EQ(ref.stats.pyramid_level, 1);
  ASSERT_GT(ref.points.size(), 5u);
  // Some point also matched neighbours 32 and 33 (ids 42, 43: the second word of bits).
  bool second_word = false;
  for (const SweepPoint& p : ref.points) {
    second_word |= std::find(p.cameras.begin() + 2, p.cameras.end(), 42) != p.cameras.end() ||
                   std::find(p.cameras.begin() + 2, p.cameras.end(), 43) != p.cameras.end();
  }
  EXPECT_TRUE(second_word);
  ExpectSameWinners(ref, loops_->Run(job), ref.stats.median_depth, "34 neighbours");
}

TEST_F(GlslSweepTest, BlankAndFaintTexturesFindNothing) {
  const Mesh square = MakeFlatSquare(0.15, 1.3, 8);
  PyramidSceneOptions blank;
  blank.texture_contrast = 0;
  const SweepJob blank_job = MakeSmallSweepJob(MakePyramidScene(blank), square);
  PyramidSceneOptions faint;
  faint.texture_contrast = 0.015;
  SweepJob faint_job = MakeSmallSweepJob(MakePyramidScene(faint), square);
  for (GlslSweepKernel* kernel : Kernels()) {
    SCOPED_TRACE(Label(kernel));
    const SweepResult none = kernel->Run(blank_job);
    EXPECT_EQ(none.points.size(), 0u);
    EXPECT_EQ(none.stats.valid_hypotheses, 0);
    EXPECT_GT(none.stats.covered_pixels, 0);
    faint_job.options.min_texture_variance = SweepOptions().min_texture_variance;
    EXPECT_EQ(kernel->Run(faint_job).points.size(), 0u);
    faint_job.options.min_texture_variance = 0;
    EXPECT_GT(kernel->Run(faint_job).points.size(), 10u);
  }
}

// ---- Errors ----

void ExpectInputError(SweepKernel& kernel, const SweepJob& job, const std::string& fragment) {
  testing::ExpectInputError([&] { kernel.Run(job); }, {fragment});
}

TEST_F(GlslSweepTest, BadJobsThrowInputErrorLikeTheReference) {
  const SweepJob good = MakeTinyValidSweepJob();
  GlslSweepKernel& kernel = *unrolled_;
  EXPECT_NO_THROW(kernel.Run(good));

  SweepJob job = good;
  job.mesh = Mesh();
  ExpectInputError(kernel, job, "mesh has no faces");
  job = good;
  job.mesh.faces[0][1] = 1000;
  ExpectInputError(kernel, job, "refers to vertex 1000");
  job = good;
  job.mesh.vertices[0].x() = std::nan("");
  ExpectInputError(kernel, job, "not finite");
  job = good;
  job.camera.view.SetCenter({0, 0, -5});  // under the ground, looking away from the mesh
  ExpectInputError(kernel, job, "no face of the mesh is in front of the camera");
  job = good;
  job.camera.image = cv::Mat();
  ExpectInputError(kernel, job, "camera 0 ('pyramid_0'): image missing");
  job = good;
  job.neighbours[1].image = cv::Mat(31, 40, CV_32F, cv::Scalar(0.5));
  ExpectInputError(kernel, job,
                   "neighbour 2 ('pyramid_2'): image is 40x31 but the view's intrinsics say 40x30");
  job = good;
  job.neighbours[0].image.convertTo(job.neighbours[0].image, CV_8U, 255);
  ExpectInputError(kernel, job, "CV_32FC1");
  job = good;
  job.neighbours.clear();
  ExpectInputError(kernel, job, "no neighbour");
  job = good;
  job.neighbours[0].view.SetCenter(job.camera.view.Center());
  ExpectInputError(kernel, job, "at the camera's centre");
  job = good;
  job.camera.view.intrinsics.k1 = 0.1;
  ExpectInputError(kernel, job, "distortion");
  job = good;
  job.options.ncc_threshold = 2;
  ExpectInputError(kernel, job, "--sweep.ncc-threshold");
  // Beyond the driver's texture size.
  job = good;
  const int huge = kernel.gl_info().max_texture_size + 1;
  job.camera.view.intrinsics.width = huge;
  job.camera.view.intrinsics.cx = huge / 2.0;
  job.camera.image = cv::Mat(30, huge, CV_32F, cv::Scalar(0.5));
  job.options.max_image_dimension = 0;
  ExpectInputError(kernel, job, "texture size limit");
  // A capture of an offset the job does not sweep.
  GlslSweepCapture capture;
  capture.offset = 50;
  try {
    kernel.Run(good, &capture);
    ADD_FAILURE() << "no error for a capture of offset 50";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("offset 50"), std::string::npos) << e.what();
  }
  // The kernel still works after all these.
  EXPECT_NO_THROW(kernel.Run(good));
}

TEST_F(GlslSweepTest, ShaderCompileFailureIsReadable) {
  GlslSweepKernelOptions options;
  options.shader_defines = {"vec4 vec5"};  // every sweep shader now names an unknown type
  try {
    GlslSweepKernel kernel(*context_, options);
    ADD_FAILURE() << "the broken shaders compiled";
  } catch (const InternalError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("failed to compile"), std::string::npos) << what;
    EXPECT_NE(what.find("sweep_raster"), std::string::npos) << what;
    EXPECT_NE(what.find("error"), std::string::npos) << what;         // the driver's message
    EXPECT_NE(what.find("    > sweep_"), std::string::npos) << what;  // and the source line
  }
  options.shader_defines.clear();
  options.blur_block = 100;
  EXPECT_THROW(GlslSweepKernel(*context_, options), InputError);
}

// ---- Factory ----

TEST_F(GlslSweepTest, FactoryMakesKernelsByName) {
  EXPECT_EQ(MakeSweepKernel("reference")->Name(), "reference");
  EXPECT_EQ(MakeSweepKernel("glsl")->Name(), "glsl");
  EXPECT_EQ(MakeSweepKernel("cpu")->Name(), "cpu");
  std::string why;
  EXPECT_EQ(MakeSweepKernel("auto", {}, &why)->Name(), context_->info().software ? "cpu" : "glsl");
  EXPECT_NE(why.find(context_->info().renderer), std::string::npos) << why;
  try {
    MakeSweepKernel("cuda");
    ADD_FAILURE() << "no error for an unknown kernel";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("auto, glsl, cpu, reference"), std::string::npos);
  }
  // Bad options are the caller's error even for "auto" (no silent fallback).
  GlslSweepKernelOptions bad;
  bad.max_batch_bytes = -1;
  EXPECT_THROW(MakeSweepKernel("auto", bad), InputError);
  // A kernel made by the factory owns its context and binds it only while it runs, so it
  // works on its own thread and then on other threads in turn (the worker process runs each
  // job on a fresh thread).
  const SweepJob job = MakeSmallSweepJob(NoisyPyramidScene(), MakeFlatSquare(0.15, 1.3, 2));
  GlslSweepKernelOptions loops;
  loops.blur = GlslBlurVariant::kLoops;
  std::unique_ptr<SweepKernel> kernel = MakeSweepKernel("auto", loops);
  const size_t here = kernel->Run(job).points.size();
  EXPECT_GT(here, 10u);
  for (int round = 0; round < 2; ++round) {
    size_t there = 0;
    std::thread other([&] { there = kernel->Run(job).points.size(); });
    other.join();
    EXPECT_EQ(there, here);
  }
  context_->MakeCurrent();  // back to the suite's context
}

}  // namespace
}  // namespace ms
