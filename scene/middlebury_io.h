// Middlebury multi-view stereo camera files (*_par.txt), cameras only: the image count, then per
// image "name k11 .. k33 r11 .. r33 t1 t2 t3" with P = K [R | t] (R world -> camera). Image
// sizes are not in the file; they come from the images (named relative to the file's folder).
#pragma once

#include <string>

#include "scene/image_io.h"
#include "scene/scene.h"
#include "scene/scene_io.h"

namespace ms {

Scene ParseMiddlebury(const std::string& name, std::string contents,
                      const ImageSizeLookup& image_size);

Scene ReadMiddlebury(const std::string& path, const SceneReadOptions& options);

// Lossy: distortion, all points.
void WriteMiddlebury(const Scene& scene, const std::string& path, const SceneWriteOptions& options);

}  // namespace ms
