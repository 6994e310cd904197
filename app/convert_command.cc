// `manisweep convert`: reads a scene in one format and writes it in another (see
// docs/reference/formats.md for what each format holds and what a conversion loses).
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "base/error.h"
#include "scene/scene_io.h"

namespace ms::app {
namespace {

struct ConvertOptions {
  std::string input;          // scene to read
  std::string output;         // path to write
  std::string from = "auto";  // input format name, or auto (detected from the path)
  std::string to = "auto";    // output format name, or auto (inferred from the output path)
  SceneReadOptions read;
  SceneWriteOptions write;
  std::string keep_views;  // "0-14,20": only these views (and the points two of them see)
};

// "0-14,20" -> {0, ..., 14, 20}. Throws InputError naming the option.
std::vector<int> ParseViewList(const std::string& text) {
  std::vector<int> views;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    int first = 0, last = 0;
    char dash = 0, rest = 0;
    std::stringstream range(item);
    if (range >> first) {
      last = first;
      if (range >> dash && (dash != '-' || !(range >> last))) first = -1;
      if (range >> rest) first = -1;
    } else {
      first = -1;
    }
    if (first < 0 || last < first) {
      throw InputError("--keep-views: '" + item + "' is not a view index or a range A-B");
    }
    for (int v = first; v <= last; ++v) views.push_back(v);
  }
  if (views.empty()) throw InputError("--keep-views: no view given");
  return views;
}

void RunConvert(const ConvertOptions& options) {
  const SceneFormat from = ParseSceneFormat(options.from);
  const SceneFormat to =
      options.to == "auto" ? InferOutputFormat(options.output) : ParseSceneFormat(options.to);
  Scene scene = ReadScene(options.input, options.read, from);
  if (!options.keep_views.empty()) scene = SubsetOfViews(scene, ParseViewList(options.keep_views));
  WriteScene(scene, options.output, to, options.write);
}

}  // namespace

void RegisterConvertCommand(CLI::App& app) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* cmd = app.add_subcommand(
      "convert",
      "Convert a scene between formats: COLMAP (text/binary), NVM, Bundler, openMVG, Strecha "
      "and Middlebury cameras");
  cmd->add_option("-i,--input", options->input, "scene to read (file or directory)")->required();
  cmd->add_option("-o,--output", options->output, "where to write the scene")->required();
  const std::string formats =
      "colmap-text, colmap-binary, nvm, bundler, openmvg, strecha, middlebury, h5 or auto";
  cmd->add_option("--from", options->from, "input format: " + formats)->capture_default_str();
  cmd->add_option("--to", options->to,
                  "output format: " + formats +
                      " (auto: from the output path; a directory becomes COLMAP text)")
      ->capture_default_str();
  cmd->add_option("--image-dir", options->read.image_dir,
                  "folder with the images, when they are not beside the model or in an images/ "
                  "folder next to it (NVM, Bundler and Middlebury need them for image sizes)");
  cmd->add_option("--nvm-model", options->read.nvm_model_index,
                  "which model of a multi-model NVM file to read (0 = first)")
      ->capture_default_str();
  cmd->add_flag("--require-images", options->read.require_images,
                "fail if an image file of the scene cannot be found");
  cmd->add_option("--keep-views", options->keep_views,
                  "write only these views (indices in the order read, e.g. 0-14,20) and the "
                  "points at least two of them see: a part of the images, to extend later "
                  "(docs/design/extend.md)");
  cmd->add_flag("--allow-lossy", options->write.allow_lossy,
                "write even if the output format cannot hold everything (e.g. Bundler and "
                "fx != fy); each kind of loss is logged as a warning");
  cmd->callback([options] { RunConvert(*options); });
}

}  // namespace ms::app
