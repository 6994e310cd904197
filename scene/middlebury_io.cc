#include "scene/middlebury_io.h"

#include <fmt/format.h>

#include "base/error.h"
#include "base/file_util.h"
#include "base/text_reader.h"
#include "scene/format_util.h"

namespace ms {

Scene ParseMiddlebury(const std::string& name, std::string contents,
                      const ImageSizeLookup& image_size) {
  const size_t file_bytes = contents.size();
  TextReader r(name, std::move(contents));
  const int64_t count = format::NextInt(r, "number of images", 0, INT32_MAX);
  Scene scene;
  scene.source = name;
  scene.views.reserve(format::ReserveBound(count, file_bytes, 44));
  for (int64_t i = 0; i < count; ++i) {
    View view;
    view.name = std::string(r.NextToken("image name"));
    Eigen::Matrix3d K, R;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) K(a, b) = format::NextDouble(r, "K");
    }
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) R(a, b) = format::NextDouble(r, "R");
    }
    for (int a = 0; a < 3; ++a) view.t[a] = format::NextDouble(r, "t");
    view.intrinsics = format::IntrinsicsFromK(r, K, "K of " + format::Quote(view.name));
    view.R = format::NearestRotation(R);
    scene.views.push_back(std::move(view));
  }
  if (!r.AtEnd()) {
    r.Fail("unexpected data after the " + std::to_string(count) +
           " images the first line announces");
  }
  // Sizes last, so a malformed file fails before any image is looked up.
  for (View& view : scene.views) {
    const ImageSize size = image_size(view.name);
    view.intrinsics.width = size.width;
    view.intrinsics.height = size.height;
  }
  return scene;
}

Scene ReadMiddlebury(const std::string& path, const SceneReadOptions& options) {
  format::ImageLocator locator(path, options);
  Scene scene = ParseMiddlebury(path, ReadFileToString(path), [&](const std::string& image) {
    return locator.RequireSize(image, "because Middlebury files do not store it");
  });
  locator.AttachImages(&scene);
  return scene;
}

void WriteMiddlebury(const Scene& scene, const std::string& path,
                     const SceneWriteOptions& options) {
  format::LossPolicy loss(path, "Middlebury cameras", options.allow_lossy);
  if (!scene.points.empty()) loss.Report("the points (Middlebury files hold cameras only)");
  using format::FormatDouble;
  std::string out = fmt::format("{}\n", scene.views.size());
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    format::RequireTokenName(path, "Middlebury", i, v.name);
    const Intrinsics& k = v.intrinsics;
    if (k.HasDistortion()) loss.Report("lens distortion");
    out += fmt::format("{} {} 0 {} 0 {} {} 0 0 1", v.name, FormatDouble(k.fx), FormatDouble(k.cx),
                       FormatDouble(k.fy), FormatDouble(k.cy));
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) out += " " + FormatDouble(v.R(a, b));
    }
    out += fmt::format(" {} {} {}\n", FormatDouble(v.t.x()), FormatDouble(v.t.y()),
                       FormatDouble(v.t.z()));
  }
  WriteFileAtomically(
      path, [&](std::ostream& s) { s.write(out.data(), out.size()); }, false);
}

}  // namespace ms
