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

#include "coordinator/run_store.h"
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
  DepthErrorStats refined;  // with --refine only
  MeshReport check;
  int64_t jobs_smoothed = 0;  // over all iterations (run.h5, /stats/iterations)
};

// Open3D's verdict on `files` (tests/tools/open3d_verdict.py): watertight, or with `open` edge-
// and vertex-manifold, and no self-intersecting pair. Skipped, saying so, without Open3D.
void ExpectOpen3dClean(const std::string& files, bool open) {
  const std::string verdict = std::string("/usr/bin/python3 ") + MS_SOURCE_DIR +
                              "/tests/tools/open3d_verdict.py" + (open ? " --open" : "") + files;
  const int status = std::system(verdict.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << verdict;
  if (WEXITSTATUS(status) == 77) {
    std::printf("NOTE: Open3D is not importable with /usr/bin/python3: its verdict is skipped\n");
    return;
  }
  EXPECT_EQ(WEXITSTATUS(status), 0) << verdict;
}

// Every mesh the run wrote passes check-mesh (exact and floating point; the surfaces proper have
// a boundary) and Open3D's verdict as a user loading it gets it.
void ExpectCleanForUsers(const std::string& out, bool refined) {
  std::string closed_files, surface_files;
  if (refined) {
    const MeshReport report = CheckMesh(ReadMesh(out + "/refined.ply"), MeshCheckOptions{});
    EXPECT_TRUE(report.is_valid) << out << "/refined.ply\n" << report.ToTable();
    closed_files += " " + out + "/refined.ply";
  }
  for (const char* name : {"initial", "final"}) {
    for (const bool surface : {false, true}) {
      const std::string path = out + "/" + name + (surface ? "_surface" : "") + ".ply";
      MeshCheckOptions options;
      options.allow_boundary = surface;
      const MeshReport report = CheckMesh(ReadMesh(path), options);
      EXPECT_TRUE(report.is_valid) << path << "\n" << report.ToTable();
      (surface ? surface_files : closed_files) += " " + path;
    }
  }
  ExpectOpen3dClean(closed_files, /*open=*/false);
  ExpectOpen3dClean(surface_files, /*open=*/true);
}

// `image_noise`: Gaussian pixel noise in grey levels, independent per image; `point_noise`:
// Gaussian noise on the sparse points' positions (scene units).
// `options`: extra coordinator options (the sweep's travel with the jobs). `refine`: the
// coordinator also refines final.ply with the default refinement, on the same workers.
Outcome Reconstruct(const std::string& scene_name, const gl::GlContext& gl, double image_noise,
                    double point_noise, const std::string& options, bool refine) {
  const fs::path root = fs::path(::testing::TempDir()) /
                        ("ms_pyramid_" + scene_name + "_noise" + std::to_string(image_noise) + "_" +
                         std::to_string(point_noise) + (options.empty() ? "" : "_options"));
  fs::remove_all(root);
  SynthOptions synth;
  synth.scene = scene_name;  // the defaults: 16 views, 800 x 600, the 4 base corners
  synth.image_noise = image_noise;
  synth.point_noise = point_noise;
  WriteSynthDataset(MakeSynthDataset(synth, &gl), (root / "data").string());
  const std::string out = (root / "run").string();
  fs::create_directories(out);
  const int port = test::FreePort();
  const std::string endpoint = "tcp://127.0.0.1:" + std::to_string(port);
  ChildProcess coordinator(
      MS_BINARY,
      Split("coordinator --input " + (root / "data" / "scene.h5").string() + " --bind " + endpoint +
            " --output " + out + " --max-iterations 15 --progress-interval 5" +
            (refine ? " --refine" : "") + (options.empty() ? "" : " " + options)),
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
  ExpectCleanForUsers(out, refine);
  for (const IterationStats& s : ReadRunFile(out + "/run.h5").iterations) {
    outcome.jobs_smoothed += s.jobs_smoothed;
  }
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
  if (refine) {
    const Mesh refined = ReadMesh(out + "/refined.ply");
    const Evaluation r = EvaluateMeshes(gl, {{"refined", &refined}}, ground_truth, scene, options);
    std::printf("%s", FormatEvaluationTable(r).c_str());
    outcome.refined = r.meshes[0].total;
  }
  if (!::testing::Test::HasFailure()) fs::remove_all(root);
  return outcome;
}

// One row of Table 1 and its regression bounds. A run is deterministic (the points are
// inserted sorted by camera and pixel), but its trajectory depends on the last bits of its input:
// the rows without noise (closed, surface proper, and refined) are bounded about 5% above the
// worst of ten variants that must not matter (bench/accuracy_variants.py: seeds 1-4, scene.h5,
// COLMAP text and binary, NVM; docs/design/accuracy.md, "One run is a draw"), of which this test
// runs one (seed 1, scene.h5); the noisy rows about 5% above their one measured run. The workers
// run the CPU kernel, auto's choice on a CPU machine, named so that a GPU machine measures the same
// thing; other kernels give other figures within about +-0.003 (docs/design/sweep.md, "Which kernel
// auto picks"), and so do other CPUs (docs/design/accuracy.md). The closed mesh is the headline
// (every pixel); the surface proper covers fewer.
struct Table1Row {
  const char* scene;
  double image_noise;  // grey levels
  double point_noise;  // scene units
  double initial_mae_above, closed_mae_at_most, surface_mae_at_most, surface_coverage_at_least;
  const char* options = "";  // coordinator options beyond the defaults
  // > 0: the coordinator also refines (the default refinement, the paper's Table 2), and the
  // refined closed mesh's MAE is at most this.
  double refined_mae_at_most = 0;
};

void ExpectTable1Row(const Table1Row& row) {
  const gl::GlContext gl;
  const bool refine = row.refined_mae_at_most > 0;
  const Outcome o =
      Reconstruct(row.scene, gl, row.image_noise, row.point_noise, row.options, refine);
  EXPECT_TRUE(o.check.is_closed_manifold) << o.check.ToTable();
  EXPECT_GT(o.initial.mae, row.initial_mae_above);  // the flat base square
  EXPECT_LE(o.closed.mae, row.closed_mae_at_most);
  EXPECT_DOUBLE_EQ(o.closed.coverage, 1.0);
  EXPECT_LE(o.surface.mae, row.surface_mae_at_most);
  EXPECT_GE(o.surface.coverage, row.surface_coverage_at_least);
  if (refine) {
    EXPECT_LE(o.refined.mae, row.refined_mae_at_most);
    EXPECT_DOUBLE_EQ(o.refined.coverage, 1.0);
  }
  // The workers' noise estimates reach the coordinator's statistics: noisy images are smoothed,
  // clean ones not (docs/design/sweep.md, "Noisy images").
  if (row.image_noise > 0) {
    EXPECT_GT(o.jobs_smoothed, 0);
  } else {
    EXPECT_EQ(o.jobs_smoothed, 0);
  }
}

// Bounds: the worsts of docs/results/accuracy_pyramid-down_defaults.json (swept) and of
// accuracy_pyramid-down_refine-sigma6.json (refined by the defaults).
// Paper: 0.108 -> 0.013 m swept, 0.002 m refined (Table 2).
TEST(PyramidAccuracy, DownwardPyramidReproducesTables1And2) {
  ExpectTable1Row({"pyramid-down", 0, 0, 0.07, 0.0087, 0.0043, 0.92, "", 0.0009});
}

// Bounds: the worsts of docs/results/accuracy_pyramid-up_defaults.json (swept) and of
// accuracy_pyramid-up_refine-sigma6.json (refined by the defaults).
// Paper: 0.135 -> 0.028 m swept, 0.012 m refined (Table 2).
TEST(PyramidAccuracy, UpwardPyramidReproducesTables1And2) {
  ExpectTable1Row({"pyramid-up", 0, 0, 0.09, 0.0055, 0.0039, 0.92, "", 0.00052});
}

// With 2 grey levels of Gaussian noise in every image (docs/design/accuracy.md, "Table 1 with noisy
// inputs"), which the sweep smooths away before matching (docs/design/sweep.md, "Noisy images"),
// and with 5 grey levels plus sparse points moved by 1% of the viewing distance (0.03). Without the
// smoothing (--sweep.image-noise-target 0) the upward pyramid with 5 grey levels finds no point.
// One run each: the noisy rows are not yet distributions, and are bounded about 5% above the
// figures in docs/design/accuracy.md, "Table 1 with noisy inputs".
TEST(PyramidAccuracy, DownwardPyramidWithImageNoise) {
  ExpectTable1Row({"pyramid-down", 2, 0, 0.07, 0.0046, 0.0043, 0.965});
}

TEST(PyramidAccuracy, UpwardPyramidWithImageNoise) {
  ExpectTable1Row({"pyramid-up", 2, 0, 0.09, 0.0037, 0.0028, 0.95});
}

TEST(PyramidAccuracy, DownwardPyramidWithStrongImageNoiseAndNoisyPoints) {
  ExpectTable1Row({"pyramid-down", 5, 0.03, 0.07, 0.0108, 0.0068, 0.945});
}

TEST(PyramidAccuracy, UpwardPyramidWithStrongImageNoiseAndNoisyPoints) {
  ExpectTable1Row({"pyramid-up", 5, 0.03, 0.09, 0.0057, 0.0053, 0.95});
}

// The paper's rule: k = 0 competes like any offset, and a pixel fewer neighbours see needs only
// those. Its loop stalls on points it already has (docs/design/accuracy.md, "Winners that move
// the surface", which gives this run's figures; bounded about 10% above them).
constexpr const char* kPaperRule = "--sweep.winners-must-move=false --sweep.strict-support=false";

TEST(PyramidAccuracy, DownwardPyramidWithThePapersRule) {
  ExpectTable1Row({"pyramid-down", 0, 0, 0.07, 0.0134, 0.0121, 0.92, kPaperRule});
}

TEST(PyramidAccuracy, UpwardPyramidWithThePapersRule) {
  ExpectTable1Row({"pyramid-up", 0, 0, 0.09, 0.0085, 0.0042, 0.895, kPaperRule});
}

}  // namespace
}  // namespace ms
