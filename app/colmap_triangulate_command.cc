// `manisweep colmap-triangulate`: the documented route from cameras with known poses (Strecha,
// Middlebury, or any scene format) to a sparse point cloud with visibility, through Debian's
// colmap. See docs/reference/colmap-route.md and colmap/colmap_triangulate.h.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include "app/commands.h"
#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "colmap/colmap_triangulate.h"
#include "scene/scene_io.h"

namespace fs = std::filesystem;

namespace ms::app {
namespace {

struct ColmapTriangulateCommandOptions {
  std::string input;        // cameras with known poses (any scene format)
  std::string images;       // folder with the images, if not where the format says
  std::string output;       // scene to write: .h5, a COLMAP directory, or another points format
  std::string to = "auto";  // output format name, or auto (from the output path)
  ColmapTriangulateOptions colmap;
};

// Writes the scene so that `path` is either the complete result or untouched: file formats are
// written atomically by WriteScene; a COLMAP directory is written beside it and moved in.
void WriteOutputAtomically(const Scene& scene, const std::string& path, SceneFormat format) {
  if (format != SceneFormat::kColmapText && format != SceneFormat::kColmapBinary) {
    WriteScene(scene, path, format);
    return;
  }
  fs::path final_path = fs::path(path).lexically_normal();
  if (!final_path.has_filename()) final_path = final_path.parent_path();  // "dir/"
  const fs::path temp = TempPathFor(final_path);
  std::error_code ec;
  fs::remove_all(temp, ec);
  try {
    WriteScene(scene, temp.string(), format);
  } catch (...) {
    fs::remove_all(temp, ec);
    throw;
  }
  fs::path old;
  if (fs::exists(final_path, ec)) {
    old = fs::path(final_path.string() + ".old-" + std::to_string(::getpid()));
    fs::remove_all(old, ec);
    fs::rename(final_path, old, ec);
    if (ec) {
      fs::remove_all(temp, ec);
      throw InputError(final_path.string() +
                       ": cannot replace the existing model: " + ec.message());
    }
  }
  fs::rename(temp, final_path, ec);
  if (ec) {
    const std::string message = ec.message();
    if (!old.empty()) fs::rename(old, final_path, ec);
    fs::remove_all(temp, ec);
    throw InputError(final_path.string() +
                     ": cannot move the finished model into place: " + message);
  }
  if (!old.empty()) fs::remove_all(old, ec);
}

void RunColmapTriangulate(const ColmapTriangulateCommandOptions& options) {
  options.colmap.Check();
  const SceneFormat to =
      options.to == "auto" ? InferOutputFormat(options.output) : ParseSceneFormat(options.to);
  // Fail before minutes of colmap if the output cannot hold what it makes.
  if (to == SceneFormat::kStrecha || to == SceneFormat::kMiddlebury) {
    throw InputError(options.output + ": format " + SceneFormatName(to) +
                     " holds cameras only; write the points to a .h5 file or a COLMAP directory");
  }
  std::error_code ec;
  if ((to == SceneFormat::kColmapText || to == SceneFormat::kColmapBinary) &&
      fs::exists(options.output, ec) && !fs::is_directory(options.output, ec)) {
    throw InputError(options.output + ": is a file, but the output is a COLMAP model directory");
  }

  Timer total;
  SceneReadOptions read;
  read.image_dir = options.images;
  read.require_images = true;
  Scene cameras = ReadScene(options.input, read);
  if (!cameras.points.empty()) {
    spdlog::warn("{}: the input's {} points are replaced by colmap's", options.input,
                 cameras.points.size());
    cameras.points.clear();
  }
  const ColmapTriangulateResult result = TriangulateWithColmap(cameras, options.colmap);
  Timer write_timer;
  WriteOutputAtomically(result.scene, options.output, to);
  const double write_s = write_timer.Seconds();

  const Scene& scene = result.scene;
  size_t views_used = 0;
  std::vector<bool> used(scene.views.size(), false);
  for (const ScenePoint& p : scene.points) {
    for (const Observation& o : p.observations) used[o.view] = true;
  }
  std::string unused_names;
  for (size_t i = 0; i < used.size(); ++i) {
    if (used[i]) {
      ++views_used;
    } else {
      unused_names += (unused_names.empty() ? "" : ", ") + scene.views[i].name;
    }
  }
  if (views_used < scene.views.size()) {
    spdlog::warn("colmap-triangulate: {} views see no point: {}", scene.views.size() - views_used,
                 unused_names);
  }
  spdlog::info(
      "colmap-triangulate: wrote {}: {} ({} of {} views see points; poses unchanged to "
      "{:.1e})",
      options.output, scene.Summary(), views_used, scene.views.size(),
      std::max(result.max_rotation_change, result.max_translation_change));
  std::string times;
  for (const ColmapStageTime& t : result.stage_times) {
    times += fmt::format("{} {:.1f} s, ", t.stage, t.seconds);
  }
  spdlog::info("colmap-triangulate: {}write {:.1f} s; total {:.1f} s ({})", times, write_s,
               total.Seconds(), result.colmap_version);
  if (scene.points.empty()) {
    spdlog::warn(
        "colmap-triangulate: colmap triangulated no points (too little texture, or "
        "images that do not overlap?)");
  }
}

}  // namespace

void RegisterColmapTriangulateCommand(CLI::App& app) {
  auto options = std::make_shared<ColmapTriangulateCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "colmap-triangulate",
      "Sparse points with visibility for cameras with known poses (Strecha, Middlebury, any "
      "scene): runs Debian's colmap (CPU SIFT, matching, point_triangulator with the poses "
      "fixed) and imports the result. See docs/reference/colmap-route.md");
  cmd->add_option("-i,--input", options->input,
                  "cameras with known poses: a Strecha directory of *.camera files, a "
                  "Middlebury *_par.txt, or any scene format (its points are ignored)")
      ->required();
  cmd->add_option("--images", options->images,
                  "folder with the images, when they are not where the input format puts them");
  cmd->add_option("-o,--output", options->output,
                  "scene to write: *.h5, a COLMAP model directory (text unless it exists as "
                  "binary), or .nvm/.out/.json")
      ->required();
  cmd->add_option("--to", options->to,
                  "output format: colmap-text, colmap-binary, h5, nvm, bundler, openmvg or auto "
                  "(from the output path)")
      ->capture_default_str();
  ColmapTriangulateOptions& c = options->colmap;
  cmd->add_option("--workspace", c.workspace,
                  "directory for colmap's database, image links, models and colmap.log; kept. "
                  "Default: a temporary directory, removed at the end");
  cmd->add_flag("--keep-workspace", c.keep_workspace,
                "keep the temporary workspace (its path is logged)");
  cmd->add_option("--colmap", c.colmap,
                  "colmap executable: a path, or a name looked up in PATH (Debian package "
                  "`colmap`)")
      ->capture_default_str();
  cmd->add_option("--matcher", c.matcher,
                  "exhaustive (every image pair) or sequential (pairs close in name order)")
      ->capture_default_str();
  cmd->add_option("--max-image-size", c.max_image_size,
                  "SIFT on images scaled down so the longer side is at most this many pixels "
                  "(keypoints come back in full-size pixels)")
      ->capture_default_str();
  cmd->add_option("--threads", c.threads, "threads for colmap; -1 = all cores")
      ->capture_default_str();
  cmd->callback([options] { RunColmapTriangulate(*options); });
}

}  // namespace ms::app
