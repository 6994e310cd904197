#include "scene/strecha_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "base/error.h"
#include "base/file_util.h"
#include "base/text_reader.h"
#include "scene/format_util.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

constexpr int64_t kMaxSide = int64_t{1} << 20;
constexpr uintmax_t kMaxCameraFileBytes = 1 << 20;  // a camera file is ~200 bytes
const char kSuffix[] = ".camera";

bool HasCameraSuffix(const std::string& file) {
  const size_t n = sizeof(kSuffix) - 1;
  return file.size() > n && file.compare(file.size() - n, n, kSuffix) == 0;
}

std::vector<fs::path> CameraFiles(const std::string& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec) && HasCameraSuffix(it->path().filename().string())) {
      files.push_back(it->path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

View ParseStrechaCamera(const std::string& name, std::string contents) {
  TextReader r(name, std::move(contents));
  Eigen::Matrix3d K, R;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) K(i, j) = format::NextDouble(r, "K");
  }
  for (int i = 0; i < 3; ++i) {
    if (format::NextDouble(r, "distortion") != 0) {
      r.Fail("distortion: only '0 0 0' is supported (the non-zero model is undocumented)");
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) R(i, j) = format::NextDouble(r, "R (camera to world)");
  }
  Eigen::Vector3d C;
  for (int i = 0; i < 3; ++i) C[i] = format::NextDouble(r, "C (camera centre)");
  View view;
  view.intrinsics = format::IntrinsicsFromK(r, K, "K");
  view.intrinsics.width = static_cast<int>(format::NextInt(r, "image width", 1, kMaxSide));
  view.intrinsics.height = static_cast<int>(format::NextInt(r, "image height", 1, kMaxSide));
  if (!r.AtEnd()) r.Fail("unexpected data after the image size");
  std::string file = fs::path(name).filename().string();
  if (HasCameraSuffix(file)) file.resize(file.size() - (sizeof(kSuffix) - 1));
  view.name = file;
  view.R = format::NearestRotation(R.transpose());
  view.SetCenter(C);
  return view;
}

bool IsStrechaDirectory(const std::string& dir) {
  std::error_code ec;
  return fs::is_directory(dir, ec) && !CameraFiles(dir).empty();
}

Scene ReadStrecha(const std::string& dir, const SceneReadOptions& options) {
  RequireDirectory(dir, "Strecha camera directory");
  const std::vector<fs::path> files = CameraFiles(dir);
  if (files.empty()) throw InputError(dir + ": no *.camera files in this directory");
  Scene scene;
  scene.source = dir;
  for (const fs::path& file : files) {
    scene.views.push_back(
        ParseStrechaCamera(file.string(), ReadFileToString(file, kMaxCameraFileBytes)));
  }
  format::ImageLocator(dir, options).AttachImages(&scene);
  return scene;
}

void WriteStrecha(const Scene& scene, const std::string& dir, const SceneWriteOptions& options) {
  format::LossPolicy loss(dir, "Strecha cameras", options.allow_lossy);
  if (!scene.points.empty()) loss.Report("the points (Strecha files hold cameras only)");
  std::set<std::string> names;
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const std::string file = fs::path(scene.views[i].name).filename().string();
    if (file.empty() || !names.insert(file).second) {
      throw InputError(dir + ": view " + std::to_string(i) + ": image file name " +
                       format::Quote(file) + " is empty or used twice");
    }
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir + ": cannot create directory: " + ec.message());
  using format::FormatDouble;
  for (const View& v : scene.views) {
    const Intrinsics& k = v.intrinsics;
    if (k.HasDistortion()) loss.Report("lens distortion");
    const Eigen::Matrix3d Rc = v.R.transpose();  // camera -> world
    const Eigen::Vector3d c = v.Center();
    std::string out = fmt::format("{} 0 {}\n0 {} {}\n0 0 1\n0 0 0\n", FormatDouble(k.fx),
                                  FormatDouble(k.cx), FormatDouble(k.fy), FormatDouble(k.cy));
    for (int a = 0; a < 3; ++a) {
      out += fmt::format("{} {} {}\n", FormatDouble(Rc(a, 0)), FormatDouble(Rc(a, 1)),
                         FormatDouble(Rc(a, 2)));
    }
    out += fmt::format("{} {} {}\n{} {}\n", FormatDouble(c.x()), FormatDouble(c.y()),
                       FormatDouble(c.z()), k.width, k.height);
    const fs::path path = fs::path(dir) / (fs::path(v.name).filename().string() + kSuffix);
    WriteFileAtomically(
        path, [&](std::ostream& s) { s.write(out.data(), out.size()); }, false);
  }
}

}  // namespace ms
