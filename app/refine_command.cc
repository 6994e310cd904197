// `manisweep refine`: photometric refinement of a mesh (refine/refiner.h, docs/design/refine.md)
// that keeps it a closed 2-manifold without self-intersections. The per-pair gradients run on this
// machine's cores, or on workers (RefineWorkers: `reconstruct --refine`, `coordinator --refine`).
#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/option_registration.h"
#include "app/process_control.h"
#include "app/refine_run.h"
#include "base/error.h"
#include "base/log.h"
#include "coordinator/refine_dispatcher.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "proto/content_hash.h"
#include "refine/refine_checkpoint.h"
#include "refine/refiner.h"
#include "scene/scene_io.h"
#include "sweep/sweep_images.h"

namespace ms::app {
namespace {

struct RefineCommandOptions {
  std::string input, mesh, output;
  bool ascii = false;
  bool resume = false;
  RefineOptions refine;
  NeighbourOptions neighbours;
};

void LogIteration(const RefineIteration& it) {
  spdlog::info(
      "iteration {} (level {}, {} vertices): energy {:.4f} over {} pixels{}; step x{:.3g}: {} "
      "vertices moved ({} halved, {} refused), largest {:.3g}; {:.2f} s ({} checks, {:.2f} s)",
      it.iteration, it.level, it.vertices, it.energy, it.pixels,
      it.rejected ? " (higher: last step undone)" : "", it.step_scale, it.moved, it.halved,
      it.refused, it.largest_move, it.seconds, it.checks, it.check_seconds);
}

void LogRemeshing(const RefineStats& stats) {
  spdlog::info(
      "remeshing: {} edges collapsed ({} refused), {} split ({} refused), {} flipped ({} "
      "refused)",
      stats.collapses, stats.collapses_refused, stats.splits, stats.splits_refused, stats.flips,
      stats.flips_refused);
}

void LogDispatch(const RefineDispatchStats& d) {
  spdlog::info(
      "refinement on workers: {} rounds, {} jobs ({} handed out again), {:.1f} MiB of jobs out, "
      "{:.1f} MiB of gradients in; {:.1f} s waiting for rounds, {:.1f} s of worker time",
      d.rounds, d.jobs, d.requeued, d.bytes_out / 1048576.0, d.bytes_in / 1048576.0, d.seconds,
      d.worker_seconds);
}

}  // namespace

void RefineMeshFile(const std::string& input, const std::string& mesh_path,
                    const std::string& output, const RefineOptions& refine,
                    const NeighbourOptions& neighbours, bool ascii, bool resume,
                    const RefineWorkers* workers) {
  refine.Check();
  neighbours.Check();
  Scene scene = ReadScene(input);
  scene.Validate();
  const std::vector<std::pair<int, int>> pairs = RefinePairs(scene, neighbours);
  if (pairs.empty()) throw InputError(input + ": no camera has a neighbour to refine with");
  // Started first: its loop answers the workers while the images and the mesh load.
  std::unique_ptr<RefineDispatcher> dispatcher;
  if (workers) {
    dispatcher = std::make_unique<RefineDispatcher>(scene, pairs, refine, workers->transport,
                                                    workers->scheduler, workers->limits,
                                                    workers->stop_requested);
  }
  Mesh mesh = ReadMesh(mesh_path);
  // What a checkpoint is valid for: the same scene, starting mesh and options.
  const std::string fingerprint = fmt::format("input={} mesh={} {} {}", input, mesh_path,
                                              OptionGroupText(refine), OptionGroupText(neighbours));
  if (mesh.faces.empty()) throw InputError(mesh_path + ": the mesh has no faces");
  // A finished refinement of this very mesh (by content) with these options is not redone.
  const std::string done_fingerprint =
      fingerprint + " mesh-content=" + HashHex(HashFile(mesh_path).hash);
  if (resume && RefineIsDone(output, done_fingerprint)) {
    spdlog::info(
        "{} is up to date (refined from this {} with these options); delete it to refine "
        "again",
        output, mesh_path);
    return;
  }
  MeshCheckOptions check;
  check.allow_float_issues = true;  // reported below; refinement leaves such spots alone
  const MeshReport before = CheckMesh(mesh, check);
  if (!before.is_closed_manifold) {
    throw InputError(mesh_path + ": not a closed 2-manifold (run `manisweep check-mesh " +
                     mesh_path + "`); refine keeps a closed manifold closed, so it needs one");
  }
  // With workers, only they read the images; here the views are enough (remeshing's pixel
  // sizes).
  std::vector<SweepCamera> cameras(scene.views.size());
  for (size_t c = 0; c < scene.views.size(); ++c) {
    cameras[c] = dispatcher ? SweepCameraGeometry(static_cast<int32_t>(c), scene.views[c])
                            : LoadSweepCamera(static_cast<int32_t>(c), scene.views[c]);
  }
  spdlog::info(
      "refining {} ({} vertices, {} faces) with {} camera pairs, {} iterations over {} levels, "
      "the gradients {}",
      mesh_path, mesh.NumVertices(), mesh.NumFaces(), pairs.size(), refine.iterations,
      refine.levels, dispatcher ? "on the workers" : "in this process");
  std::optional<RefineCheckpoint> checkpoint;
  if (resume) checkpoint = ReadRefineCheckpoint(output, fingerprint);
  if (checkpoint) {
    spdlog::info("resuming from the checkpoint beside {}: {} iterations done", output,
                 checkpoint->state.iterations_done);
    mesh = std::move(checkpoint->mesh);
  } else if (resume) {
    spdlog::info("no checkpoint beside {}: starting afresh", output);
  }
  InstallStopSignals();
  const auto save = [&](const Mesh& current, const RefineState& state) {
    WriteRefineCheckpoint(output, current, state, fingerprint);
    if (StopRequested()) {
      spdlog::warn("interrupted after iteration {}; continue with the same command and --resume",
                   state.iterations_done);
      throw CommandExit(kExitInterrupted);
    }
  };
  RefineHooks hooks;
  hooks.progress = LogIteration;
  if (checkpoint) hooks.resume = &checkpoint->state;
  hooks.checkpoint = save;
  if (dispatcher) hooks.pair_gradients = dispatcher->Source();
  RefineStats stats;
  try {
    stats = RefineMesh(&mesh, cameras, pairs, refine, hooks);
  } catch (const RefineInterrupted&) {
    if (StopRequested()) {
      spdlog::warn("interrupted; the last checkpoint stays: continue with --resume");
      throw CommandExit(kExitInterrupted);
    }
    throw InputError(
        "refinement stopped: no worker is left to compute the gradients (see the log above); "
        "the last checkpoint stays: continue with --resume");
  }
  if (refine.max_edge_px > 0) LogRemeshing(stats);
  if (dispatcher) {
    LogDispatch(dispatcher->stats());
    dispatcher.reset();  // the workers are told to shut down
  }
  MeshWriteOptions write_options;
  write_options.binary = !ascii;
  WriteMesh(mesh, output, write_options);
  RemoveRefineCheckpoint(output);
  WriteRefineDone(output, done_fingerprint, stats, OptionGroupValues(refine));
  const MeshReport after = CheckMesh(mesh);
  std::printf("refined %s -> %s: %d iterations, %.1f s, final energy %.4f; check-mesh: %s\n",
              mesh_path.c_str(), output.c_str(), static_cast<int>(stats.iterations.size()),
              stats.seconds, stats.final_energy,
              after.is_valid ? "valid (closed 2-manifold, no self-intersection, float-robust)"
                             : "NOT VALID");
  if (!after.is_valid) {
    for (const std::string& problem : after.Problems()) std::printf("  %s\n", problem.c_str());
    if (before.is_valid) {
      throw InternalError("refinement made a valid mesh invalid");
    }
  }
}

void RegisterRefineCommand(CLI::App& app) {
  auto options = std::make_shared<RefineCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "refine",
      "Photometric refinement of a closed manifold mesh (Vu et al. 2012) that keeps it a closed "
      "2-manifold without self-intersections (docs/design/refine.md)");
  cmd->add_option("-i,--input", options->input, "scene with images (any supported format)")
      ->required();
  cmd->add_option("-m,--mesh", options->mesh, "closed 2-manifold to refine (.ply or .obj)")
      ->required();
  cmd->add_option("-o,--output", options->output, "refined mesh to write (.ply or .obj)")
      ->required();
  cmd->add_flag("--ascii", options->ascii, "write ASCII PLY instead of binary");
  cmd->add_flag("--resume", options->resume,
                "continue from the checkpoint beside --output (OUTPUT.checkpoint.*, written after "
                "every iteration); starts afresh if there is none");
  AddOptionGroup(cmd, &options->refine);
  AddOptionGroup(cmd, &options->neighbours);
  cmd->callback([options] {
    RefineMeshFile(options->input, options->mesh, options->output, options->refine,
                   options->neighbours, options->ascii, options->resume);
  });
}

}  // namespace ms::app
