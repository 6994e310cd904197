// The paper's Table 1 reproduced end to end: the synthetic pyramids (manisweep synth), a
// coordinator and two sweep workers as real processes on loopback, then the independent mesh
// checker and the depth-map evaluation from view 0 (Sigma = 0.06 m, as the paper).
//
// The paper: MAE 0.108 -> 0.013 m (downward pyramid), 0.135 -> 0.028 m (upward), with
// it_max = 15 iterations, as here. The headline is the closed manifold (final.ply, every
// pixel); the surface proper (final_surface.ply: the faces with no Steiner vertex, the Steiner
// faces only closing the manifold around the cameras' free space) is measured after it.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "gl/context.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "scene/scene_io.h"
#include "tests/distributed/child_process.h"
#include "tools/evaluate.h"
#include "tools/synth.h"

namespace ms {
namespace {

namespace fs = std::filesystem;
using test::ChildProcess;

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> words;
  std::istringstream in(text);
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

struct Outcome {
  DepthErrorStats initial, surface, closed;
  MeshReport check;
};

// Every mesh the run wrote passes check-mesh (exact and floating point; the surfaces proper have
// a boundary) and Open3D's is_watertight / get_self_intersecting_triangles.
void ExpectCleanForUsers(const std::string& out) {
  std::string files;
  for (const char* name : {"initial", "final"}) {
    for (const bool surface : {false, true}) {
      const std::string path = out + "/" + name + (surface ? "_surface" : "") + ".ply";
      MeshCheckOptions options;
      options.allow_boundary = surface;
      const MeshReport report = CheckMesh(ReadMesh(path), options);
      EXPECT_TRUE(report.is_valid) << path << "\n" << report.ToTable();
      if (!surface) files += " " + path;
    }
  }
  const std::string verdict =
      std::string("/usr/bin/python3 ") + MS_SOURCE_DIR + "/tests/tools/open3d_verdict.py" + files;
  const int status = std::system(verdict.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << verdict;
  if (WEXITSTATUS(status) == 77) {
    std::printf("NOTE: Open3D is not importable with /usr/bin/python3: its verdict is skipped\n");
    return;
  }
  EXPECT_EQ(WEXITSTATUS(status), 0) << verdict;
}

// `image_noise`: Gaussian pixel noise in grey levels, independent per image.
Outcome Reconstruct(const std::string& scene_name, const gl::GlContext& gl,
                    double image_noise = 0) {
  const fs::path root = fs::path(::testing::TempDir()) /
                        ("ms_pyramid_" + scene_name + "_noise" + std::to_string(image_noise));
  fs::remove_all(root);
  SynthOptions synth;
  synth.scene = scene_name;  // the defaults: 16 views, 800 x 600, the 4 base corners
  synth.image_noise = image_noise;
  WriteSynthDataset(MakeSynthDataset(synth, &gl), (root / "data").string());
  const std::string out = (root / "run").string();
  fs::create_directories(out);
  const int port = test::FreePort();
  const std::string endpoint = "tcp://127.0.0.1:" + std::to_string(port);
  ChildProcess coordinator(
      MS_BINARY,
      Split("coordinator --input " + (root / "data" / "scene.h5").string() + " --bind " + endpoint +
            " --output " + out + " --max-iterations 15 --progress-interval 5"),
      out + "/coordinator.log");
  std::vector<std::unique_ptr<ChildProcess>> workers;
  for (const char* id : {"w1", "w2"}) {
    workers.push_back(std::make_unique<ChildProcess>(
        MS_BINARY,
        Split(std::string("worker --connect ") + endpoint + " --id " + id +
              " --kernel cpu --threads 1 --give-up-after 60 --cache-dir " +
              (root / "cache" / id).string()),
        out + "/" + id + ".log"));
  }
  EXPECT_TRUE(coordinator.Wait(600)) << coordinator.Log();
  EXPECT_EQ(coordinator.exit_code(), 0) << coordinator.Log();
  for (auto& worker : workers) EXPECT_TRUE(worker->Wait(30)) << worker->Log();

  Outcome outcome;
  const Mesh closed = ReadMesh(out + "/final.ply");
  outcome.check = CheckMesh(closed, MeshCheckOptions{});
  ExpectCleanForUsers(out);
  const Mesh initial = ReadMesh(out + "/initial_surface.ply");
  const Mesh surface = ReadMesh(out + "/final_surface.ply");
  const Scene scene = ReadScene((root / "data" / "scene.h5").string());
  const Mesh ground_truth = ReadMesh((root / "data" / "gt.ply").string());
  EvaluateOptions options;
  options.sigma = 0.06;
  const Evaluation e =
      EvaluateMeshes(gl, {{"initial", &initial}, {"surface", &surface}, {"closed", &closed}},
                     ground_truth, scene, options);
  std::printf("%s, image noise %g\n%s", scene_name.c_str(), image_noise,
              FormatEvaluationTable(e).c_str());
  outcome.initial = e.meshes[0].total;
  outcome.surface = e.meshes[1].total;
  outcome.closed = e.meshes[2].total;
  if (!::testing::Test::HasFailure()) fs::remove_all(root);
  return outcome;
}

// Regression bounds about 5% above the measured values (docs/performance.md; the runs are
// deterministic: the points are inserted sorted by camera and pixel). The workers run the CPU
// kernel, auto's choice on a CPU machine, named so that a GPU machine measures the same thing;
// other kernels give other figures within about +-0.003 (docs/sweep.md, "Which kernel auto
// picks"). The closed mesh is the headline (every pixel); the surface proper covers fewer.
TEST(PyramidAccuracy, DownwardPyramidReproducesTable1) {
  const gl::GlContext gl;
  const Outcome o = Reconstruct("pyramid-down", gl);
  EXPECT_TRUE(o.check.is_closed_manifold) << o.check.ToTable();
  EXPECT_GT(o.initial.mae, 0.07);   // the flat base square (paper: 0.108)
  EXPECT_LE(o.closed.mae, 0.0147);  // measured 0.0140; paper: 0.013
  EXPECT_DOUBLE_EQ(o.closed.coverage, 1.0);
  EXPECT_LE(o.surface.mae, 0.0124);      // measured 0.0118
  EXPECT_GE(o.surface.coverage, 0.915);  // measured 0.922
}

TEST(PyramidAccuracy, UpwardPyramidReproducesTable1) {
  const gl::GlContext gl;
  const Outcome o = Reconstruct("pyramid-up", gl);
  EXPECT_TRUE(o.check.is_closed_manifold) << o.check.ToTable();
  EXPECT_GT(o.initial.mae, 0.09);   // paper: 0.135
  EXPECT_LE(o.closed.mae, 0.0127);  // measured 0.0121; paper: 0.028
  EXPECT_DOUBLE_EQ(o.closed.coverage, 1.0);
  EXPECT_LE(o.surface.mae, 0.0072);     // measured 0.0068
  EXPECT_GE(o.surface.coverage, 0.87);  // measured 0.880
}

// With 2 grey levels of Gaussian noise in every image (docs/performance.md, "Table 1 with noisy
// inputs"): the paper's t_NCC = 0.98 still finds the surface; the upward pyramid loses more to
// the closure wedges at the image borders than the downward one.
TEST(PyramidAccuracy, DownwardPyramidWithImageNoise) {
  const gl::GlContext gl;
  const Outcome o = Reconstruct("pyramid-down", gl, /*image_noise=*/2);
  EXPECT_TRUE(o.check.is_closed_manifold) << o.check.ToTable();
  EXPECT_LE(o.closed.mae, 0.0149);  // measured 0.0142; without noise 0.0141
  EXPECT_DOUBLE_EQ(o.closed.coverage, 1.0);
  EXPECT_LE(o.surface.mae, 0.0092);      // measured 0.0087
  EXPECT_GE(o.surface.coverage, 0.905);  // measured 0.913
}

TEST(PyramidAccuracy, UpwardPyramidWithImageNoise) {
  const gl::GlContext gl;
  const Outcome o = Reconstruct("pyramid-up", gl, /*image_noise=*/2);
  EXPECT_TRUE(o.check.is_closed_manifold) << o.check.ToTable();
  EXPECT_LE(o.closed.mae, 0.0224);  // measured 0.0213; without noise 0.0097
  EXPECT_DOUBLE_EQ(o.closed.coverage, 1.0);
  EXPECT_LE(o.surface.mae, 0.0174);      // measured 0.0165
  EXPECT_GE(o.surface.coverage, 0.835);  // measured 0.845
}

}  // namespace
}  // namespace ms
