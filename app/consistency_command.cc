// `manisweep consistency`: the ground-truth-free quality figure of meshes of a real scene
// (tools/consistency.h): the share of image pixels where a neighbour's image, reprojected through
// the mesh, matches the camera's own (NCC above a threshold). Several meshes are compared on the
// same pixels, e.g. the initial and final meshes of a run; --within restricts them to the pixels
// another mesh covers (a peer's open mesh).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/option_registration.h"
#include "mesh/mesh_io.h"
#include "scene/scene_io.h"
#include "tools/consistency.h"

namespace ms::app {
namespace {

struct ConsistencyCommandOptions {
  std::string input;
  std::vector<std::string> meshes;
  std::string within;
  bool per_camera = false;
  ConsistencyOptions consistency;
};

void RunConsistency(const ConsistencyCommandOptions& options) {
  Scene scene = ReadScene(options.input);
  scene.Validate();
  std::printf(
      "photo-consistency: share of pixels whose NCC (sigma %.3g px) against a neighbour "
      "reprojected through the mesh is above %.2f; %s\n",
      options.consistency.sweep.gaussian_sigma_px, options.consistency.ncc_threshold,
      options.consistency.sweep.max_image_dimension > 0
          ? ("images halved until they fit " +
             std::to_string(options.consistency.sweep.max_image_dimension) + " px")
                .c_str()
          : "full-size images");
  std::unique_ptr<Mesh> within;
  if (!options.within.empty()) {
    within = std::make_unique<Mesh>(ReadMesh(options.within));
    std::printf("only the pixels %s covers count\n", options.within.c_str());
  }
  std::printf("%-40s %10s %10s %10s %11s\n", "mesh", "consistent", "covered", "of covered",
              "pixels");
  for (const std::string& path : options.meshes) {
    const Mesh mesh = ReadMesh(path);
    const ConsistencyReport report =
        MeasureConsistency(scene, mesh, options.consistency, within.get());
    const CameraConsistency& t = report.total;
    const auto pct = [](int64_t a, int64_t b) { return b > 0 ? 100.0 * a / b : 0.0; };
    std::printf("%-40s %9.1f%% %9.1f%% %9.1f%% %11lld\n", path.c_str(), pct(t.consistent, t.pixels),
                pct(t.covered, t.pixels), pct(t.consistent, t.covered),
                static_cast<long long>(t.pixels));
    if (options.per_camera) std::printf("%s", report.ToTable().c_str());
  }
}

}  // namespace

void RegisterConsistencyCommand(CLI::App& app) {
  auto options = std::make_shared<ConsistencyCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "consistency",
      "Ground-truth-free quality of meshes: share of pixels where the neighbours' images, "
      "reprojected through the mesh, match (NCC)");
  cmd->add_option("-i,--input", options->input, "scene with images (any supported format)")
      ->required();
  cmd->add_option("-m,--mesh", options->meshes, "meshes to measure (.ply or .obj), repeatable")
      ->required();
  cmd->add_option("--threshold", options->consistency.ncc_threshold,
                  "a pixel is consistent if its NCC with a neighbour is above this")
      ->capture_default_str();
  cmd->add_option("--within", options->within,
                  "count only the pixels this mesh covers (.ply or .obj; e.g. an open mesh of "
                  "another tool, to compare on the same pixels)");
  cmd->add_flag("--per-camera", options->per_camera, "also print one line per camera");
  AddOptionGroup(cmd, &options->consistency.neighbours);
  AddOptionGroup(cmd, &options->consistency.sweep);
  cmd->callback([options] { RunConsistency(*options); });
}

}  // namespace ms::app
