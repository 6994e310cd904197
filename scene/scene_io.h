// Reading and writing scenes in the formats of the field. The project's own canonical store is
// HDF5 (.h5); the others are importers/exporters. Every reader checks what it reads and throws
// InputError naming the file, line (or byte) and field; none trusts counts from the file.
#pragma once

#include <string>

#include "scene/scene.h"

namespace ms {

enum class SceneFormat {
  kAuto,          // decide from the path (see DetectSceneFormat)
  kManisweepH5,   // scene.h5
  kColmapText,    // directory with cameras.txt, images.txt, points3D.txt
  kColmapBinary,  // directory with cameras.bin, images.bin, points3D.bin
  kNvm,           // VisualSFM NVM_V3 .nvm
  kBundler,       // bundle.out (+ list.txt beside it)
  kOpenMvg,       // sfm_data.json
  kStrecha,       // directory of *.camera files (cameras only)
  kMiddlebury,    // *_par.txt (cameras only)
};

// "colmap-text", "colmap-binary", "nvm", "bundler", "openmvg", "strecha", "middlebury", "h5",
// "auto". Throws InputError for an unknown name.
SceneFormat ParseSceneFormat(const std::string& name);
std::string SceneFormatName(SceneFormat format);

struct SceneReadOptions {
  // Where images live when the format stores names relative to something else; default: the
  // format's own convention (next to the file, or COLMAP's parent "images/" folder, ...).
  std::string image_dir;
  int nvm_model_index = 0;      // NVM files may hold several models
  bool require_images = false;  // fail if an image file is missing
  // Check image sizes against the files (reads only headers). NVM, Bundler and Middlebury lack
  // sizes and always read them from the images.
  bool read_image_sizes = true;
  void Check() const;  // throws InputError naming the field
};

struct SceneWriteOptions {
  // Formats that cannot hold part of a scene (e.g. Bundler: fx != fy, an off-centre principal
  // point, tangential distortion; camera-only formats: the points) fail with InputError saying
  // what would be lost. With allow_lossy they write what they can and log a warning per kind.
  bool allow_lossy = false;
};

// Detects by extension/contents: *.h5, *.nvm, *.json, bundle.out/*.out, *_par.txt, a directory
// with cameras.{txt,bin} (COLMAP; a "sparse/" or "sparse/0/" subfolder is looked into), or a
// directory of *.camera files.
SceneFormat DetectSceneFormat(const std::string& path);

Scene ReadScene(const std::string& path, const SceneReadOptions& options = {},
                SceneFormat format = SceneFormat::kAuto);

// The format a path asks for when writing: *.h5, *.nvm, *.out (Bundler), *.json (openMVG),
// *_par.txt (Middlebury); an existing COLMAP model directory keeps its flavour; any other path
// is a COLMAP text model directory. Strecha output must be asked for by name.
SceneFormat InferOutputFormat(const std::string& path);

// Writes atomically (temporary name, then rename; directory formats write each file so).
// Directory formats create the directory. kAuto uses InferOutputFormat. Throws InputError if
// the format cannot hold the scene without loss (see SceneWriteOptions) or writing fails.
void WriteScene(const Scene& scene, const std::string& path, SceneFormat format,
                const SceneWriteOptions& options = {});

}  // namespace ms
