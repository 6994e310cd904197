#include "scene/scene_io.h"

#include <filesystem>

#include "base/error.h"

namespace fs = std::filesystem;

namespace ms {

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
    case SceneFormat::kAuto: return "auto";
    case SceneFormat::kManisweepH5: return "h5";
    case SceneFormat::kColmapText: return "colmap-text";
    case SceneFormat::kColmapBinary: return "colmap-binary";
    case SceneFormat::kNvm: return "nvm";
    case SceneFormat::kBundler: return "bundler";
    case SceneFormat::kOpenMvg: return "openmvg";
    case SceneFormat::kStrecha: return "strecha";
    case SceneFormat::kMiddlebury: return "middlebury";
  }
  return "unknown";
}

SceneFormat DetectSceneFormat(const std::string& path) {
  throw InputError(path + ": scene formats are not implemented yet");
}

Scene ReadScene(const std::string& path, const SceneReadOptions&, SceneFormat) {
  throw InputError(path + ": scene formats are not implemented yet");
}

void WriteScene(const Scene&, const std::string& path, SceneFormat) {
  throw InputError(path + ": scene formats are not implemented yet");
}

}  // namespace ms
