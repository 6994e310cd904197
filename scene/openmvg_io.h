// openMVG's sfm_data.json (cereal JSON archive, sfm_data_version 0.x).
//
// Views with a pose and an intrinsic become scene views (ordered by view id); intrinsics
// "pinhole", "pinhole_radial_k1", "pinhole_radial_k3" and "pinhole_brown_t2" (k1 k2 k3 t1 t2 =
// OpenCV's k1 k2 k3 p1 p2) convert exactly, other types fail when a posed view uses them.
// Extrinsics are world->camera rotations with camera centres. Landmarks carry no colour (points
// get the default grey); their observations give the pixel coordinates.
#pragma once

#include <string>

#include "scene/scene.h"
#include "scene/scene_io.h"

namespace ms {

// Parses sfm_data.json held in memory. `root_path` (may be null) receives the file's root_path,
// where openMVG keeps the images.
Scene ParseOpenMvg(const std::string& name, const std::string& contents, std::string* root_path);

Scene ReadOpenMvg(const std::string& path, const SceneReadOptions& options);

// Writes sfm_data.json that openMVG loads. Lossy: fx != fy (one focal length), point colours.
void WriteOpenMvg(const Scene& scene, const std::string& path, const SceneWriteOptions& options);

}  // namespace ms
