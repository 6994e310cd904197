// `manisweep synth <scene> --output DIR`: a synthetic dataset with exact ground truth
// (tools/synth.h, docs/reference/synth.md).
#include <memory>
#include <optional>

#include "app/commands.h"
#include "app/option_registration.h"
#include "base/log.h"
#include "gl/context.h"
#include "tools/synth.h"

namespace ms::app {
namespace {

struct SynthCommandOptions {
  SynthOptions synth;
  std::string output;
  bool no_images = false;
  gl::GlBackendOption gl;
};

void RunSynth(SynthCommandOptions options) {
  options.synth.render_images = !options.no_images;
  options.synth.Check();
  Timer timer;
  std::optional<gl::GlContext> context;
  if (options.synth.render_images) {
    gl::GlContextOptions gl_options;
    gl_options.backend = options.gl.gl_backend;
    context.emplace(gl_options);
    spdlog::info("OpenGL: {}", context->info().Summary());
  }
  const SynthDataset dataset = MakeSynthDataset(options.synth, context ? &*context : nullptr);
  WriteSynthDataset(dataset, options.output);
  spdlog::info(
      "synth {}: wrote {} in {:.1f} s (geometry {:.2f} s, points {:.2f} s, images "
      "{:.2f} s)",
      dataset.scene_name, options.output, timer.Seconds(), dataset.seconds_geometry,
      dataset.seconds_points, dataset.seconds_images);
}

}  // namespace

void RegisterSynthCommand(CLI::App& app) {
  auto options = std::make_shared<SynthCommandOptions>();
  SynthOptions& s = options->synth;
  CLI::App* cmd = app.add_subcommand(
      "synth",
      "Write a synthetic dataset with exact ground truth: rendered images, cameras, a sparse "
      "cloud with visibility (COLMAP text in sparse/, scene.h5) and the ground-truth mesh "
      "(gt.ply). See docs/reference/synth.md");
  cmd->add_option("scene", s.scene, "pyramid-down, pyramid-up (the paper's), blob or city")
      ->required()
      ->check(CLI::IsMember({"pyramid-down", "pyramid-up", "blob", "city"}));
  cmd->add_option("-o,--output", options->output, "dataset directory (created)")->required();
  cmd->add_option("--views", s.views,
                  "number of cameras; 0: the scene's default (pyramids 16, blob 24, city 60)")
      ->capture_default_str();
  cmd->add_option("--width", s.width, "image width; 0: default (800, city 1024)")
      ->capture_default_str();
  cmd->add_option("--height", s.height, "image height; 0: default (600, city 768)")
      ->capture_default_str();
  cmd->add_option("--seed", s.seed, "seed of texture, blob shape, city layout, points and noise")
      ->capture_default_str();
  cmd->add_option("--image-noise", s.image_noise,
                  "standard deviation of Gaussian pixel noise, grey levels (0-255)")
      ->capture_default_str();
  cmd->add_option("--point-noise", s.point_noise,
                  "standard deviation of Gaussian noise on sparse point positions, scene units "
                  "(metres)")
      ->capture_default_str();
  cmd->add_option("--points", s.points,
                  "blob/city: sparse points wanted; 0: 3000 (blob), 40 per view (city); the "
                  "pyramids always get their 4 base corners")
      ->capture_default_str();
  cmd->add_option("--min-track", s.min_track, "keep sparse points seen by at least this many views")
      ->capture_default_str();
  cmd->add_option("--max-grazing", s.max_grazing_deg,
                  "a point is seen only if its surface is within this angle (degrees) of facing "
                  "the camera")
      ->capture_default_str();
  cmd->add_option("--supersampling", s.supersampling, "anti-aliasing: k x k samples per pixel")
      ->capture_default_str();
  cmd->add_option("--texture-photos", s.texture_photos,
                  "photographs (files or directories of .jpg/.png) mixed into the procedural "
                  "texture, e.g. ../shared/data/fountain-P11/images");
  cmd->add_flag("--no-images", options->no_images,
                "write cameras, points and meshes only (no rendering, no OpenGL needed)");
  AddOptionGroup(cmd, &options->gl);
  cmd->callback([options] { RunSynth(*options); });
}

}  // namespace ms::app
