#include "scene/scene_io.h"

#include <cctype>
#include <filesystem>

#include "base/error.h"
#include "scene/scene_h5.h"

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
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".h5" || extension == ".hdf5") return SceneFormat::kManisweepH5;
  throw InputError(path + ": scene formats are not implemented yet");
}

Scene ReadScene(const std::string& path, const SceneReadOptions&, SceneFormat format) {
  if (format == SceneFormat::kAuto) format = DetectSceneFormat(path);
  if (format == SceneFormat::kManisweepH5) return ReadSceneH5(path);
  throw InputError(path + ": scene formats are not implemented yet");
}

void WriteScene(const Scene& scene, const std::string& path, SceneFormat format) {
  if (format == SceneFormat::kAuto) format = DetectSceneFormat(path);
  if (format == SceneFormat::kManisweepH5) return WriteSceneH5(scene, path);
  throw InputError(path + ": scene formats are not implemented yet");
}

}  // namespace ms
