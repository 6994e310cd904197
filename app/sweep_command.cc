// `manisweep sweep`: one camera's mesh sweep (paper section 2.2, docs/design/sweep.md), for
// debugging and benchmarking: reads the scene and the mesh, picks the camera's neighbours and the
// part of the mesh it sees, sweeps, and writes the points found (PLY, NCC as the "quality" scalar).
#include <fmt/ranges.h>

#include <memory>
#include <string>

#include "app/commands.h"
#include "app/option_registration.h"
#include "base/error.h"
#include "base/log.h"
#include "gl/context.h"
#include "mesh/mesh_io.h"
#include "mesh/visible_mesh.h"
#include "scene/scene_io.h"
#include "scene/view_selection.h"
#include "sweep/sweep_images.h"
#include "sweep/sweep_kernel_factory.h"

namespace ms::app {
namespace {

struct SweepCommandOptions {
  std::string input;
  std::string mesh;
  int camera = 0;
  std::string output;
  SweepKernelChoice kernel;
  bool reference = false;
  gl::GlBackendOption gl;
  NeighbourOptions neighbours;
  SweepOptions sweep;
};

void RunSweep(const SweepCommandOptions& options) {
  options.sweep.Check();
  options.kernel.Check();
  options.neighbours.Check();
  GlslSweepKernelOptions glsl;
  glsl.context.backend = options.gl.gl_backend;
  // The GL context (and its shaders) before reading anything: a missing driver fails fast.
  std::string why;
  std::unique_ptr<SweepKernel> kernel =
      MakeSweepKernel(options.reference ? "reference" : options.kernel.kernel, glsl, &why);
  spdlog::info("sweep: {} kernel ({})", kernel->Name(), why);
  if (const auto* g = dynamic_cast<const GlslSweepKernel*>(kernel.get())) {
    spdlog::info("sweep: GLSL kernel on {}", g->gl_info().Summary());
  }
  Timer timer;
  Scene scene = ReadScene(options.input);
  scene.Validate();
  const int camera = options.camera;
  if (camera < 0 || camera >= static_cast<int>(scene.views.size())) {
    throw InputError(options.input + ": --camera " + std::to_string(camera) +
                     " is not a view of the scene (it has " + std::to_string(scene.views.size()) +
                     " views)");
  }
  const std::vector<int> neighbours = SelectNeighbours(scene, camera, options.neighbours);
  if (neighbours.empty()) {
    throw InputError(options.input + ": camera " + std::to_string(camera) +
                     " has no neighbour within the viewing-angle bound");
  }
  const Mesh mesh = ReadMesh(options.mesh);
  SweepJob job;
  job.camera = LoadSweepCamera(camera, scene.views[camera]);
  for (int n : neighbours) job.neighbours.push_back(LoadSweepCamera(n, scene.views[n]));
  job.mesh = ExtractVisibleMesh(mesh, job.camera.view).mesh;
  job.options = options.sweep;
  spdlog::info("sweep: camera {} with neighbours {}; {} of {} faces visible; loaded in {:.2f} s",
               camera, fmt::join(neighbours, ", "), job.mesh.NumFaces(), mesh.NumFaces(),
               timer.Seconds());

  const SweepResult result = kernel->Run(job);
  spdlog::info("sweep ({}): {} points; {}", kernel->Name(), result.points.size(),
               result.stats.Summary());

  PointCloud cloud;
  for (const SweepPoint& p : result.points) {
    cloud.points.push_back(p.position);
    cloud.scalars.push_back(p.ncc);
  }
  WritePointCloud(cloud, options.output);
  spdlog::info("sweep: wrote {} ({} points), {:.2f} s in all", options.output, cloud.points.size(),
               timer.Seconds());
}

}  // namespace

void RegisterSweepCommand(CLI::App& app) {
  auto options = std::make_shared<SweepCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "Mesh sweeping for one camera: new 3D points near the mesh (paper section 2.2)");
  cmd->add_option("-i,--input", options->input, "scene (any supported format)")->required();
  cmd->add_option("-m,--mesh", options->mesh, "current mesh (.ply or .obj)")->required();
  cmd->add_option("-c,--camera", options->camera, "index of the camera C to sweep from")
      ->capture_default_str();
  cmd->add_option("-o,--output", options->output, "points found (.ply, NCC as 'quality')")
      ->required();
  AddOptionGroup(cmd, &options->kernel);
  cmd->add_flag("--reference", options->reference, "same as --kernel reference");
  AddOptionGroup(cmd, &options->gl);
  AddOptionGroup(cmd, &options->neighbours);
  AddOptionGroup(cmd, &options->sweep);
  cmd->callback([options] { RunSweep(*options); });
}

}  // namespace ms::app
