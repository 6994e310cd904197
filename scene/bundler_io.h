// Bundler's bundle.out (v0.3) with the image list (list.txt) beside it.
//
// Bundler's camera looks down -z with y up, and measures pixels from the image centre with y up:
// we flip y and z of the camera frame (R' = diag(1,-1,-1) R, t' = diag(1,-1,-1) t) and map a
// measurement (x, y) to (W/2 + x, H/2 - y). Its distortion f*(1 + k1 r^2 + k2 r^4) on normalised
// coordinates is OpenCV's radial model with k3 = 0, so it converts exactly. Cameras with f = 0
// (not reconstructed) are skipped with their observations. Image sizes come from the images.
#pragma once

#include <string>

#include "scene/image_io.h"
#include "scene/scene.h"
#include "scene/scene_io.h"

namespace ms {

// Parses bundle.out and list.txt held in memory.
Scene ParseBundler(const std::string& bundle_name, std::string bundle, const std::string& list_name,
                   const std::string& list, const ImageSizeLookup& image_size);

// The list file a writer puts beside `bundle_path`: "list.txt" for bundle.out, otherwise
// "<stem>.list.txt" (COLMAP's export names "X.bundle.out" + "X.list.txt").
std::string BundlerListPath(const std::string& bundle_path);

// Reads bundle.out; the list is BundlerListPath(path), else list.txt beside it or one folder up.
Scene ReadBundler(const std::string& path, const SceneReadOptions& options);

void WriteBundler(const Scene& scene, const std::string& path, const SceneWriteOptions& options);

}  // namespace ms
