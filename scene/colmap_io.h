// COLMAP sparse models: cameras, images and points3D, as .txt or .bin (COLMAP 3.x layout).
//
// Camera models read: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, and FULL_OPENCV
// when k4 = k5 = k6 = 0; other models fail (naming the model) when an image uses them. Views are
// ordered by image id, points by point id; a point's observations take their pixel coordinates
// from the image's POINTS2D entry its track names. Writing picks the simplest exact model and
// shares one camera among views with identical intrinsics.
#pragma once

#include <string>

#include "scene/scene.h"
#include "scene/scene_io.h"

namespace ms {

// The three files of one model held in memory, with the names used in error messages.
struct ColmapFiles {
  std::string cameras_name, cameras;
  std::string images_name, images;
  std::string points_name, points;
};

// Parses a model from memory; no files are touched (image paths stay empty). Throws InputError
// naming the file and line (text) or byte (binary) and the field.
Scene ParseColmapModel(ColmapFiles files, bool binary);

// The directory holding cameras.{txt,bin} for `path`: the path itself, its sparse/ or its
// sparse/0/ subfolder. Empty if none has one.
std::string FindColmapModelDir(const std::string& path);
// True if `model_dir` holds a binary model (cameras.bin), false for text (cameras.txt).
bool ColmapModelIsBinary(const std::string& model_dir);

// Reads the model in `path` (see FindColmapModelDir) and resolves image paths.
Scene ReadColmapModel(const std::string& path, bool binary, const SceneReadOptions& options);

// Writes cameras, images, points3D (.txt or .bin) into `dir`, creating it.
void WriteColmapModel(const Scene& scene, const std::string& dir, bool binary,
                      const SceneWriteOptions& options);

}  // namespace ms
