#include "scene/scene_io.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "base/log.h"
#include "scene/bundler_io.h"
#include "scene/colmap_io.h"
#include "scene/middlebury_io.h"
#include "scene/nvm_io.h"
#include "scene/openmvg_io.h"
#include "scene/scene_h5.h"
#include "scene/strecha_io.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The format named by a file name, or kAuto if the name says nothing.
SceneFormat FormatFromName(const std::string& path) {
  const std::string name = Lower(fs::path(path).filename().string());
  if (EndsWith(name, ".h5") || EndsWith(name, ".hdf5")) return SceneFormat::kManisweepH5;
  if (EndsWith(name, ".nvm")) return SceneFormat::kNvm;
  if (EndsWith(name, ".json")) return SceneFormat::kOpenMvg;
  if (EndsWith(name, ".out")) return SceneFormat::kBundler;
  if (EndsWith(name, "_par.txt")) return SceneFormat::kMiddlebury;
  return SceneFormat::kAuto;
}

// The format named by the first bytes of a file, or kAuto.
SceneFormat FormatFromContents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[32] = {};
  in.read(head, sizeof(head));
  const std::string start(head, static_cast<size_t>(in.gcount()));
  if (start.rfind("\x89HDF\r\n\x1a\n", 0) == 0) return SceneFormat::kManisweepH5;
  if (start.rfind("NVM_V3", 0) == 0) return SceneFormat::kNvm;
  if (start.rfind("# Bundle file", 0) == 0) return SceneFormat::kBundler;
  const size_t first = start.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && start[first] == '{') return SceneFormat::kOpenMvg;
  return SceneFormat::kAuto;
}

}  // namespace

SceneFormat ParseSceneFormat(const std::string& name) {
  if (name == "auto") return SceneFormat::kAuto;
  if (name == "h5") return SceneFormat::kManisweepH5;
  if (name == "colmap-text") return SceneFormat::kColmapText;
  if (name == "colmap-binary") return SceneFormat::kColmapBinary;
  if (name == "nvm") return SceneFormat::kNvm;
  if (name == "bundler") return SceneFormat::kBundler;
  if (name == "openmvg") return SceneFormat::kOpenMvg;
  if (name == "strecha") return SceneFormat::kStrecha;
  if (name == "middlebury") return SceneFormat::kMiddlebury;
  throw InputError("unknown scene format '" + name +
                   "' (use h5, colmap-text, colmap-binary, nvm, bundler, openmvg, strecha, "
                   "middlebury or auto)");
}

std::string SceneFormatName(SceneFormat format) {
  switch (format) {
    case SceneFormat::kAuto:
      return "auto";
    case SceneFormat::kManisweepH5:
      return "h5";
    case SceneFormat::kColmapText:
      return "colmap-text";
    case SceneFormat::kColmapBinary:
      return "colmap-binary";
    case SceneFormat::kNvm:
      return "nvm";
    case SceneFormat::kBundler:
      return "bundler";
    case SceneFormat::kOpenMvg:
      return "openmvg";
    case SceneFormat::kStrecha:
      return "strecha";
    case SceneFormat::kMiddlebury:
      return "middlebury";
  }
  return "unknown";
}

void SceneReadOptions::Check() const {
  if (nvm_model_index < 0) {
    throw InputError("nvm_model_index: must be >= 0, got " + std::to_string(nvm_model_index));
  }
  std::error_code ec;
  if (!image_dir.empty() && !fs::is_directory(image_dir, ec)) {
    throw InputError("image_dir: " + image_dir + " is not a directory");
  }
}

SceneFormat DetectSceneFormat(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": scene not found");
  if (fs::is_directory(path, ec)) {
    const std::string model = FindColmapModelDir(path);
    if (!model.empty()) {
      return ColmapModelIsBinary(model) ? SceneFormat::kColmapBinary : SceneFormat::kColmapText;
    }
    if (IsStrechaDirectory(path)) return SceneFormat::kStrecha;
    throw InputError(path +
                     ": cannot tell the scene format: the directory has no COLMAP model "
                     "(cameras.txt/.bin, also in sparse/ and sparse/0/) and no *.camera files; "
                     "name the format (--from)");
  }
  SceneFormat format = FormatFromName(path);
  if (format == SceneFormat::kAuto) format = FormatFromContents(path);
  if (format == SceneFormat::kAuto) {
    throw InputError(path +
                     ": cannot tell the scene format from the name or the first bytes; "
                     "name the format (--from)");
  }
  return format;
}

SceneFormat InferOutputFormat(const std::string& path) {
  const SceneFormat by_name = FormatFromName(path);
  if (by_name != SceneFormat::kAuto) return by_name;
  const std::string model = FindColmapModelDir(path);
  if (!model.empty() && ColmapModelIsBinary(model)) return SceneFormat::kColmapBinary;
  return SceneFormat::kColmapText;
}

Scene ReadScene(const std::string& path, const SceneReadOptions& options, SceneFormat format) {
  options.Check();
  const Timer timer;
  if (format == SceneFormat::kAuto) format = DetectSceneFormat(path);
  Scene scene;
  switch (format) {
    case SceneFormat::kAuto:  // resolved above
    case SceneFormat::kManisweepH5:
      scene = ReadSceneH5(path);
      break;
    case SceneFormat::kColmapText:
      scene = ReadColmapModel(path, false, options);
      break;
    case SceneFormat::kColmapBinary:
      scene = ReadColmapModel(path, true, options);
      break;
    case SceneFormat::kNvm:
      scene = ReadNvm(path, options);
      break;
    case SceneFormat::kBundler:
      scene = ReadBundler(path, options);
      break;
    case SceneFormat::kOpenMvg:
      scene = ReadOpenMvg(path, options);
      break;
    case SceneFormat::kStrecha:
      scene = ReadStrecha(path, options);
      break;
    case SceneFormat::kMiddlebury:
      scene = ReadMiddlebury(path, options);
      break;
  }
  scene.Validate();
  spdlog::info("read {} ({}) in {:.2f} s: {}", path, SceneFormatName(format), timer.Seconds(),
               scene.Summary());
  return scene;
}

void WriteScene(const Scene& scene, const std::string& path, SceneFormat format,
                const SceneWriteOptions& options) {
  if (format == SceneFormat::kAuto) format = InferOutputFormat(path);
  scene.Validate();
  switch (format) {
    case SceneFormat::kAuto:
    case SceneFormat::kManisweepH5:
      WriteSceneH5(scene, path);
      break;
    case SceneFormat::kColmapText:
      WriteColmapModel(scene, path, false, options);
      break;
    case SceneFormat::kColmapBinary:
      WriteColmapModel(scene, path, true, options);
      break;
    case SceneFormat::kNvm:
      WriteNvm(scene, path, options);
      break;
    case SceneFormat::kBundler:
      WriteBundler(scene, path, options);
      break;
    case SceneFormat::kOpenMvg:
      WriteOpenMvg(scene, path, options);
      break;
    case SceneFormat::kStrecha:
      WriteStrecha(scene, path, options);
      break;
    case SceneFormat::kMiddlebury:
      WriteMiddlebury(scene, path, options);
      break;
  }
  spdlog::info("wrote {} ({}): {}", path, SceneFormatName(format), scene.Summary());
}

}  // namespace ms
