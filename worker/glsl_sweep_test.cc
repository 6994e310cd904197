// The GLSL sweep kernel against the C++ reference (docs/sweep.md "The GLSL kernel"): per stage
// (swept mesh seen from C, shadow maps, reprojection, NCC) and end to end, for both blur
// variants, on llvmpipe in CI (on a GPU where there is one).
#include "worker/glsl_sweep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <opencv2/core.hpp>

#include "base/error.h"
#include "gl/context.h"
#include "mesh/visible_mesh.h"
#include "worker/reference_sweep.h"
#include "worker/sweep_kernel_factory.h"
#include "worker/sweep_test_scene.h"

namespace ms {
namespace {

class GlslSweepTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    context_ = new gl::GlContext();
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
    delete context_;
  }
  static std::vector<GlslSweepKernel*> Kernels() { return {loops_, unrolled_}; }
  static std::string Label(const GlslSweepKernel* k) {
    return k->blur_variant() == GlslBlurVariant::kLoops ? "loops" : "unrolled";
  }
  static gl::GlContext* context_;
  static GlslSweepKernel* loops_;
  static GlslSweepKernel* unrolled_;
};
gl::GlContext* GlslSweepTest::context_ = nullptr;
GlslSweepKernel* GlslSweepTest::loops_ = nullptr;
GlslSweepKernel* GlslSweepTest::unrolled_ = nullptr;

// The reference test's job: the flat square at half the pyramid's height, small window/tiles.
SweepJob MakeJob(const PyramidScene& scene, const Mesh& mesh) {
  SweepJob job;
  job.camera = scene.cameras[0];
  job.neighbours = {scene.cameras[1], scene.cameras[2]};
  job.mesh = ExtractVisibleMesh(mesh, job.camera.view).mesh;
  job.options.gaussian_sigma_px = 4;
  job.options.tile_size_px = 10;
  return job;
}

const PyramidScene& NoisyPyramid() {
  static const PyramidScene scene = [] {
    PyramidSceneOptions options;
    options.noise_stddev = 0.01;
    return MakePyramidScene(options);
  }();
  return scene;
}

TEST_F(GlslSweepTest, EndToEndSmoke) {
  const SweepJob job = MakeJob(NoisyPyramid(), MakeFlatSquare(0.15, 1.3, 8));
  const SweepResult reference = ReferenceSweepKernel().Run(job);
  for (GlslSweepKernel* kernel : Kernels()) {
    SweepResult glsl = kernel->Run(job);
    glsl = kernel->Run(job);
    std::printf("%s: %zu points (reference %zu); %s\n", Label(kernel).c_str(),
                glsl.points.size(), reference.points.size(), glsl.stats.Summary().c_str());
    EXPECT_NEAR(static_cast<double>(glsl.points.size()), reference.points.size(), 5);
  }
}

}  // namespace
}  // namespace ms
