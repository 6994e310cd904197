#include "scene/bundler_io.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>

#include "base/error.h"
#include "base/file_util.h"
#include "base/text_reader.h"
#include "scene/format_util.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

using format::FormatDouble;
using format::NextDouble;
using format::NextInt;

// Bundler's camera frame (y up, looking down -z) <-> ours (y down, looking down +z).
const Eigen::Matrix3d& Flip() {
  static const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
  return flip;
}

std::vector<std::string> ParseList(const std::string& list_name, const std::string& list) {
  TextReader r(list_name, list);
  std::vector<std::string> names;
  std::string_view line;
  while (r.NextDataLine(&line, 0)) {
    // "<image> [0 <focal from EXIF>]": only the name matters.
    std::string_view name;
    format::FieldCursor(line).Next(&name);
    names.emplace_back(name);
  }
  return names;
}

}  // namespace

Scene ParseBundler(const std::string& bundle_name, std::string bundle, const std::string& list_name,
                   const std::string& list, const ImageSizeLookup& image_size) {
  const std::vector<std::string> names = ParseList(list_name, list);
  const size_t file_bytes = bundle.size();
  TextReader r(bundle_name, std::move(bundle));
  std::string_view header;
  if (!r.NextDataLine(&header, 0)) r.Fail("empty file, expected '# Bundle file v0.3'");
  if (Trim(header) != "# Bundle file v0.3") {
    r.Fail("not a Bundler v0.3 file: the first line must be '# Bundle file v0.3', found " +
           format::Quote(Trim(header)));
  }
  const int64_t num_cameras = NextInt(r, "number of cameras", 0, INT32_MAX);
  const int64_t num_points = NextInt(r, "number of points", 0, INT32_MAX);
  if (static_cast<int64_t>(names.size()) != num_cameras) {
    throw InputError(list_name + ": lists " + std::to_string(names.size()) + " images but " +
                     bundle_name + " has " + std::to_string(num_cameras) + " cameras");
  }
  Scene scene;
  scene.source = bundle_name;
  std::vector<int32_t> view_of_camera(num_cameras, -1);
  size_t skipped = 0;
  for (int64_t i = 0; i < num_cameras; ++i) {
    const int line = r.line_number() + 1;
    const double f = NextDouble(r, "focal length");
    const double k1 = NextDouble(r, "k1");
    const double k2 = NextDouble(r, "k2");
    Eigen::Matrix3d R;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) R(a, b) = NextDouble(r, "rotation");
    }
    Eigen::Vector3d t;
    for (int a = 0; a < 3; ++a) t[a] = NextDouble(r, "translation");
    if (f == 0) {  // a camera Bundler could not register
      ++skipped;
      continue;
    }
    if (!(f > 0)) {
      throw InputError(bundle_name + ":" + std::to_string(line) + ": camera " + std::to_string(i) +
                       ": focal length must be positive");
    }
    const ImageSize size = image_size(names[i]);
    View view;
    view.name = names[i];
    view.intrinsics.width = size.width;
    view.intrinsics.height = size.height;
    view.intrinsics.fx = view.intrinsics.fy = f;
    view.intrinsics.cx = 0.5 * size.width;
    view.intrinsics.cy = 0.5 * size.height;
    view.intrinsics.k1 = k1;
    view.intrinsics.k2 = k2;
    view.R = format::NearestRotation(Flip() * R);
    view.t = Flip() * t;
    view_of_camera[i] = static_cast<int32_t>(scene.views.size());
    scene.views.push_back(std::move(view));
  }
  scene.points.reserve(format::ReserveBound(num_points, file_bytes, 14));
  size_t dropped = 0;
  for (int64_t p = 0; p < num_points; ++p) {
    ScenePoint point;
    for (int i = 0; i < 3; ++i) point.position[i] = NextDouble(r, "point position");
    for (int i = 0; i < 3; ++i)
      point.color[i] = static_cast<uint8_t>(NextInt(r, "point colour", 0, 255));
    const int64_t length = NextInt(r, "view list length", 0, INT32_MAX);
    for (int64_t m = 0; m < length; ++m) {
      const int64_t camera = NextInt(r, "view list camera", 0, num_cameras - 1);
      NextInt(r, "view list key", INT32_MIN, INT64_MAX);
      const double x = NextDouble(r, "view list x");
      const double y = NextDouble(r, "view list y");
      if (!(std::abs(x) <= format::kMaxPixel && std::abs(y) <= format::kMaxPixel)) {
        r.Fail("view list: pixel coordinate out of range");
      }
      const int32_t view = view_of_camera[camera];
      if (view < 0) {
        ++dropped;
        continue;
      }
      const Intrinsics& k = scene.views[view].intrinsics;
      point.observations.push_back(
          {view, static_cast<float>(0.5 * k.width + x), static_cast<float>(0.5 * k.height - y)});
    }
    scene.points.push_back(std::move(point));
  }
  if (!r.AtEnd()) r.Fail("unexpected data after the last point");
  if (skipped > 0) {
    spdlog::info("{}: skipped {} unregistered cameras (f = 0) and {} observations in them",
                 bundle_name, skipped, dropped);
  }
  format::WarnDroppedDuplicates(bundle_name, format::SortAndDeduplicateObservations(&scene));
  return scene;
}

std::string BundlerListPath(const std::string& bundle_path) {
  const fs::path path(bundle_path);
  const std::string file = path.filename().string();
  if (file == "bundle.out") return (path.parent_path() / "list.txt").string();
  std::string stem = file;
  for (const char* suffix : {".bundle.out", ".out"}) {
    const std::string s(suffix);
    if (stem.size() > s.size() && stem.compare(stem.size() - s.size(), s.size(), s) == 0) {
      stem.resize(stem.size() - s.size());
      break;
    }
  }
  return (path.parent_path() / (stem + ".list.txt")).string();
}

Scene ReadBundler(const std::string& path, const SceneReadOptions& options) {
  const fs::path bundle(path);
  std::error_code ec;
  const fs::path folder = fs::absolute(bundle, ec).parent_path();
  std::string list_path;
  for (const fs::path& candidate :
       {fs::path(BundlerListPath(path)), folder / "list.txt", folder.parent_path() / "list.txt"}) {
    if (fs::is_regular_file(candidate, ec)) {
      list_path = candidate.string();
      break;
    }
  }
  if (list_path.empty()) {
    throw InputError(path + ": image list not found (looked for " + BundlerListPath(path) +
                     ", list.txt beside the file and one folder up)");
  }
  // Bundler names images relative to the folder of list.txt.
  format::ImageLocator locator(path, options, {fs::path(list_path).parent_path()});
  Scene scene = ParseBundler(path, ReadFileToString(path), list_path, ReadFileToString(list_path),
                             [&](const std::string& image) {
                               return locator.RequireSize(
                                   image, "because Bundler measures from the image centre");
                             });
  locator.AttachImages(&scene);
  return scene;
}

void WriteBundler(const Scene& scene, const std::string& path, const SceneWriteOptions& options) {
  format::LossPolicy loss(path, "Bundler", options.allow_lossy);
  std::string list;
  std::string out =
      fmt::format("# Bundle file v0.3\n{} {}\n", scene.views.size(), scene.points.size());
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    format::RequireTokenName(path, "Bundler's list.txt", i, v.name);
    list += v.name + "\n";
    const Intrinsics& k = v.intrinsics;
    if (k.fx != k.fy) loss.Report("fx != fy (written: their mean)");
    if (k.cx != 0.5 * k.width || k.cy != 0.5 * k.height) {
      loss.Report("a principal point off the image centre");
    }
    if (k.p1 != 0 || k.p2 != 0 || k.k3 != 0) loss.Report("distortion terms p1, p2, k3");
    const Eigen::Matrix3d R = Flip() * v.R;
    const Eigen::Vector3d t = Flip() * v.t;
    out += fmt::format("{} {} {}\n", FormatDouble(0.5 * (k.fx + k.fy)), FormatDouble(k.k1),
                       FormatDouble(k.k2));
    for (int a = 0; a < 3; ++a) {
      out += fmt::format("{} {} {}\n", FormatDouble(R(a, 0)), FormatDouble(R(a, 1)),
                         FormatDouble(R(a, 2)));
    }
    out += fmt::format("{} {} {}\n", FormatDouble(t.x()), FormatDouble(t.y()), FormatDouble(t.z()));
  }
  std::vector<int64_t> next_key(scene.views.size(), 0);
  std::string views;
  for (const ScenePoint& p : scene.points) {
    views.clear();
    int count = 0;
    for (const Observation& o : p.observations) {
      double x = 0, y = 0;
      if (!format::ObservationPixel(scene, p, o, &loss, &x, &y)) continue;
      const Intrinsics& k = scene.views[o.view].intrinsics;
      views += fmt::format(" {} {} {} {}", o.view, next_key[o.view]++,
                           FormatDouble(x - 0.5 * k.width), FormatDouble(0.5 * k.height - y));
      ++count;
    }
    out += fmt::format("{} {} {}\n{} {} {}\n{}{}\n", FormatDouble(p.position.x()),
                       FormatDouble(p.position.y()), FormatDouble(p.position.z()), p.color[0],
                       p.color[1], p.color[2], count, views);
  }
  WriteFileAtomically(
      path, [&](std::ostream& s) { s.write(out.data(), out.size()); }, false);
  WriteFileAtomically(
      BundlerListPath(path), [&](std::ostream& s) { s.write(list.data(), list.size()); }, false);
}

}  // namespace ms
