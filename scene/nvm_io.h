// VisualSFM's NVM_V3 (also NVM_V3_R9T, and the "FixedK fx cx fy cy" header).
//
// A camera is "<name> <f> <qw qx qy qz> <centre xyz> <k> 0" (R9T: 9 rotation values and the
// translation t instead); measurements are pixels relative to the image centre (W/2, H/2), or to
// (cx, cy) under FixedK, so image sizes come from the image files. The radial term k is
// VisualSFM's own model on *measured* points, m_undistorted = m (1 + k |m|^2) in normalised
// units; it is converted to OpenCV's (k1, k2, k3) by a least-squares fit over the image, whose
// largest error is logged (exact when k = 0). See docs/reference/formats.md.
#pragma once

#include <string>

#include "scene/image_io.h"
#include "scene/scene.h"
#include "scene/scene_io.h"

namespace ms {

// Parses model `model_index` (0 = first) of an NVM file held in memory. Image sizes come from
// `image_size`, called once per camera of the chosen model.
Scene ParseNvm(const std::string& name, std::string contents, int model_index,
               const ImageSizeLookup& image_size);

Scene ReadNvm(const std::string& path, const SceneReadOptions& options);

// Writes NVM_V3 (one model). Views sharing one K that is not "fx = fy, centred" get a FixedK
// header; anything NVM cannot hold is a loss (see SceneWriteOptions).
void WriteNvm(const Scene& scene, const std::string& path, const SceneWriteOptions& options);

}  // namespace ms
