// `manisweep evaluate`: depth-map accuracy of meshes against a ground-truth mesh, as in the
// paper's section 3 (tools/evaluate.h, docs/reference/evaluation.md).
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands.h"
#include "app/option_registration.h"
#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "gl/context.h"
#include "mesh/mesh_io.h"
#include "scene/scene_io.h"
#include "tools/evaluate.h"

namespace ms::app {
namespace {

struct EvaluateCommandOptions {
  std::vector<std::string> meshes;
  std::vector<std::string> labels;
  std::string ground_truth;
  std::string input;
  std::vector<int> cameras;
  bool all_views = false;
  double sigma = 0;
  int max_multiple = 10;
  std::string depth = "z";
  double error_max = 0;
  std::string json;
  std::string error_image;
  std::string plot;
  gl::GlBackendOption gl;
};

void RunEvaluate(const EvaluateCommandOptions& o) {
  EvaluateOptions options;
  options.views = o.cameras;
  options.all_views = o.all_views;
  options.sigma = o.sigma;
  options.max_multiple = o.max_multiple;
  options.measure = ParseDepthMeasure(o.depth);
  options.Check();
  if (!o.labels.empty() && o.labels.size() != o.meshes.size()) {
    throw InputError("--label: give one per --mesh or none");
  }
  if (!(o.error_max >= 0)) throw InputError("--error-max: must be >= 0");
  RequireFile(o.ground_truth, "ground-truth mesh");
  const Mesh ground_truth = ReadMesh(o.ground_truth);
  std::vector<Mesh> meshes;
  std::vector<LabeledMesh> labeled;
  meshes.reserve(o.meshes.size());
  for (size_t i = 0; i < o.meshes.size(); ++i) {
    RequireFile(o.meshes[i], "mesh");
    meshes.push_back(ReadMesh(o.meshes[i]));
  }
  for (size_t i = 0; i < meshes.size(); ++i) {
    const std::string label =
        o.labels.empty() ? std::filesystem::path(o.meshes[i]).filename().string() : o.labels[i];
    labeled.push_back({label, &meshes[i]});
  }
  const Scene scene = ReadScene(o.input);
  gl::GlContextOptions gl_options;
  gl_options.backend = o.gl.gl_backend;
  const gl::GlContext context(gl_options);
  spdlog::info("OpenGL: {}", context.info().Summary());

  const Evaluation evaluation = EvaluateMeshes(context, labeled, ground_truth, scene, options);
  std::fputs(FormatEvaluationTable(evaluation).c_str(), stdout);
  EvaluationFiles files;
  files.json = o.json;
  files.error_image = o.error_image;
  files.plot = o.plot;
  files.error_max = o.error_max;
  files.ground_truth_name = o.ground_truth;
  files.scene_name = o.input;
  WriteEvaluationFiles(evaluation, files);
}

}  // namespace

void RegisterEvaluateCommand(CLI::App& app) {
  auto o = std::make_shared<EvaluateCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "evaluate",
      "Depth-map accuracy of meshes against a ground-truth mesh from the scene's cameras: MAE, "
      "MRE, RMS, coverage and the cumulative error distribution (docs/reference/evaluation.md)");
  cmd->add_option("-m,--mesh", o->meshes, "mesh(es) to evaluate (.ply/.obj); repeat to compare")
      ->required();
  cmd->add_option("--label", o->labels,
                  "names of the meshes in tables and figures (default: "
                  "file names)");
  cmd->add_option("-g,--ground-truth", o->ground_truth, "ground-truth mesh (.ply/.obj)")
      ->required();
  cmd->add_option("-i,--input", o->input, "scene with the cameras (any supported format)")
      ->required();
  auto* camera = cmd->add_option("-c,--camera", o->cameras,
                                 "view index(es) to evaluate from; default 0 (the paper: one "
                                 "chosen view)");
  cmd->add_flag("--all-views", o->all_views, "evaluate from every view of the scene")
      ->excludes(camera);
  cmd->add_option("--sigma", o->sigma,
                  "Sigma of the cumulative distribution, scene units; 0: median ground-truth "
                  "depth / 20 (the paper uses 0.06 m)")
      ->capture_default_str();
  cmd->add_option("--max-multiple", o->max_multiple, "cumulative shares for m = 1..this")
      ->capture_default_str();
  cmd->add_option("--depth", o->depth,
                  "what depth means: z (camera z, as depth maps) or range (distance from the "
                  "camera centre)")
      ->capture_default_str();
  cmd->add_option("--json", o->json, "write the results as JSON to this file");
  cmd->add_option("--error-image", o->error_image,
                  "write a PNG of the colour-mapped depth errors from the first evaluated view");
  cmd->add_option("--error-max", o->error_max,
                  "error shown as the top of the colour scale; 0: 5 Sigma")
      ->capture_default_str();
  cmd->add_option("--plot", o->plot, "write a PNG plot of the cumulative error distribution");
  AddOptionGroup(cmd, &o->gl);
  cmd->callback([o] { RunEvaluate(*o); });
}

}  // namespace ms::app
