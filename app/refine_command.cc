// `manisweep refine`: photometric refinement of a mesh (refine/refiner.h, docs/refine.md) that
// keeps it a closed 2-manifold without self-intersections. Single process for now; the
// per-pair gradients are independent and run on the machine's cores.
#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/option_registration.h"
#include "base/error.h"
#include "base/log.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "refine/refiner.h"
#include "scene/scene_io.h"
#include "sweep/sweep_images.h"

namespace ms::app {
namespace {

struct RefineCommandOptions {
  std::string input, mesh, output;
  bool ascii = false;
  RefineOptions refine;
  NeighbourOptions neighbours;
};

void RunRefine(const RefineCommandOptions& options) {
  options.refine.Check();
  options.neighbours.Check();
  Scene scene = ReadScene(options.input);
  scene.Validate();
  Mesh mesh = ReadMesh(options.mesh);
  if (mesh.faces.empty()) throw InputError(options.mesh + ": the mesh has no faces");
  MeshCheckOptions check;
  check.allow_float_issues = true;  // reported below; refinement leaves such spots alone
  const MeshReport before = CheckMesh(mesh, check);
  if (!before.is_closed_manifold) {
    throw InputError(options.mesh + ": not a closed 2-manifold (run `manisweep check-mesh " +
                     options.mesh + "`); refine keeps a closed manifold closed, so it needs one");
  }
  const std::vector<std::pair<int, int>> pairs = RefinePairs(scene, options.neighbours);
  if (pairs.empty()) throw InputError(options.input + ": no camera has a neighbour to refine with");
  std::vector<SweepCamera> cameras;
  cameras.reserve(scene.views.size());
  for (size_t c = 0; c < scene.views.size(); ++c) {
    cameras.push_back(LoadSweepCamera(static_cast<int32_t>(c), scene.views[c]));
  }
  spdlog::info(
      "refining {} ({} vertices, {} faces) with {} camera pairs, {} iterations over {} levels",
      options.mesh, mesh.NumVertices(), mesh.NumFaces(), pairs.size(), options.refine.iterations,
      options.refine.levels);
  const RefineStats stats =
      RefineMesh(&mesh, cameras, pairs, options.refine, [](const RefineIteration& it) {
        spdlog::info(
            "iteration {} (level {}): energy {:.4f} over {} pixels; {} vertices moved ({} "
            "halved, {} refused), largest {:.3g}; {:.2f} s",
            it.iteration, it.level, it.energy, it.pixels, it.moved, it.halved, it.refused,
            it.largest_move, it.seconds);
      });
  MeshWriteOptions write_options;
  write_options.binary = !options.ascii;
  WriteMesh(mesh, options.output, write_options);
  const MeshReport after = CheckMesh(mesh);
  std::printf("refined %s -> %s: %d iterations, %.1f s; check-mesh: %s\n", options.mesh.c_str(),
              options.output.c_str(), static_cast<int>(stats.iterations.size()), stats.seconds,
              after.is_valid ? "valid (closed 2-manifold, no self-intersection, float-robust)"
                             : "NOT VALID");
  if (!after.is_valid) {
    for (const std::string& problem : after.Problems()) std::printf("  %s\n", problem.c_str());
    if (after.is_closed_manifold && before.is_valid) {
      throw InternalError("refinement made a valid mesh invalid");
    }
  }
}

}  // namespace

void RegisterRefineCommand(CLI::App& app) {
  auto options = std::make_shared<RefineCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "refine",
      "Photometric refinement of a closed manifold mesh (Vu et al. 2012) that keeps it a closed "
      "2-manifold without self-intersections (docs/refine.md)");
  cmd->add_option("-i,--input", options->input, "scene with images (any supported format)")
      ->required();
  cmd->add_option("-m,--mesh", options->mesh, "closed 2-manifold to refine (.ply or .obj)")
      ->required();
  cmd->add_option("-o,--output", options->output, "refined mesh to write (.ply or .obj)")
      ->required();
  cmd->add_flag("--ascii", options->ascii, "write ASCII PLY instead of binary");
  AddOptionGroup(cmd, &options->refine);
  AddOptionGroup(cmd, &options->neighbours);
  cmd->callback([options] { RunRefine(*options); });
}

}  // namespace ms::app
