#include "scene/nvm_io.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>

#include "base/error.h"
#include "base/file_util.h"
#include "base/text_reader.h"
#include "scene/format_util.h"

namespace ms {
namespace {

using format::FormatDouble;
using format::NextDouble;
using format::NextInt;
using format::Quote;

using format::kMaxPixel;
// Conversion errors of the radial model above this (pixels) are worth a warning.
constexpr double kWarnDistortionErrorPx = 0.05;

struct RawCamera {
  std::string name;
  double f = 0;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  double k = 0;
  int line = 0;
};

struct FixedK {
  bool present = false;
  double fx = 0, cx = 0, fy = 0, cy = 0;
};

// Largest normalised radius of the image corners around (cx, cy).
double CornerRadius(const Intrinsics& k) {
  double r = 0;
  for (double x : {0.0, static_cast<double>(k.width)}) {
    for (double y : {0.0, static_cast<double>(k.height)}) {
      r = std::max(r, std::hypot((x - k.cx) / k.fx, (y - k.cy) / k.fy));
    }
  }
  return r;
}

RawCamera ParseCamera(TextReader& r, bool r9t) {
  RawCamera c;
  c.name = std::string(r.NextToken("camera file name"));
  c.line = r.line_number();
  c.f = NextDouble(r, "focal length");
  if (r9t) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) c.R(i, j) = NextDouble(r, "rotation");
    }
    for (int i = 0; i < 3; ++i) c.t[i] = NextDouble(r, "translation");
    c.R = format::NearestRotation(c.R);
  } else {
    double q[4];
    for (double& v : q) v = NextDouble(r, "quaternion");
    if (!(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) > 1e-9)) {
      r.Fail("camera " + Quote(c.name) + ": quaternion has zero length");
    }
    c.R = RotationFromQuaternion(q[0], q[1], q[2], q[3]);
    Eigen::Vector3d centre;
    for (int i = 0; i < 3; ++i) centre[i] = NextDouble(r, "camera centre");
    c.t = -c.R * centre;
  }
  c.k = NextDouble(r, "radial distortion");
  NextDouble(r, "camera terminator (0)");
  return c;
}

// The header line: the version (R9T: rotations as 3x3) and an optional FixedK.
FixedK ParseHeader(TextReader& r, bool* r9t) {
  std::string_view header;
  if (!r.NextDataLine(&header, 0)) r.Fail("empty file, expected the NVM_V3 header");
  std::string_view version;
  format::FieldCursor(header).Next(&version);
  if (version != "NVM_V3" && version != "NVM_V3_R9T") {
    r.Fail("not an NVM file: the first line must start with NVM_V3 or NVM_V3_R9T, found " +
           Quote(version));
  }
  const auto head = format::SplitFieldsAtMost(r, header, 7, "header");
  *r9t = head[0] == "NVM_V3_R9T";
  FixedK fixed;
  if (head.size() > 1) {
    if (head[1] != "FixedK" || (head.size() != 6 && head.size() != 7)) {
      r.Fail("header: expected 'FixedK fx cx fy cy [r]' after the version, found " + Quote(header));
    }
    fixed.present = true;
    fixed.fx = format::ParseDouble(r, head[2], "FixedK fx");
    fixed.cx = format::ParseDouble(r, head[3], "FixedK cx");
    fixed.fy = format::ParseDouble(r, head[4], "FixedK fy");
    fixed.cy = format::ParseDouble(r, head[5], "FixedK cy");
    if (head.size() == 7 && format::ParseDouble(r, head[6], "FixedK r") != 0) {
      r.Fail("header: a FixedK radial distortion is not supported (its model is undocumented)");
    }
    if (!(fixed.fx > 0 && fixed.fy > 0)) r.Fail("header: FixedK focal lengths must be positive");
  }
  return fixed;
}

// Camera i of the chosen model as a view: its image's size, FixedK or its focal length with the
// image centre, VisualSFM's radial distortion fitted by OpenCV's k1..k3.
View ViewOfCamera(const RawCamera& c, size_t i, const std::string& name, const FixedK& fixed,
                  const ImageSizeLookup& image_size) {
  const std::string where = name + ":" + std::to_string(c.line) + ": camera " + std::to_string(i) +
                            " (" + Quote(c.name) + ")";
  if (!(c.f > 0)) throw InputError(where + ": focal length must be positive");
  const ImageSize size = image_size(c.name);
  View view;
  view.name = c.name;
  Intrinsics& k = view.intrinsics;
  k.width = size.width;
  k.height = size.height;
  if (fixed.present) {
    k.fx = fixed.fx;
    k.fy = fixed.fy;
    k.cx = fixed.cx;
    k.cy = fixed.cy;
  } else {
    k.fx = k.fy = c.f;
    k.cx = 0.5 * size.width;
    k.cy = 0.5 * size.height;
  }
  if (c.k != 0) {
    const double error =
        format::FitOpenCvToVisualSfm(c.k, CornerRadius(k), where, &k.k1, &k.k2, &k.k3);
    const double error_px = error * std::max(k.fx, k.fy);
    if (error_px > kWarnDistortionErrorPx) {
      spdlog::warn(
          "{}: VisualSFM radial k={} converted to OpenCV k1..k3 with up to {:.3f} px "
          "error at the image corners",
          where, c.k, error_px);
    } else {
      spdlog::debug("{}: VisualSFM radial k={} -> k1={} k2={} k3={} (max error {:.2e} px)", where,
                    c.k, k.k1, k.k2, k.k3, error_px);
    }
  }
  view.R = c.R;
  view.t = c.t;
  return view;
}

// A model's points. Kept (with their observations, relative to the image centre or FixedK's
// principal point) only when `chosen`; every field is checked either way.
void ParsePoints(TextReader& r, int64_t num_cameras, bool chosen, size_t file_bytes, Scene* scene) {
  const int64_t num_points = NextInt(r, "number of points", 0, INT32_MAX);
  if (chosen) scene->points.reserve(format::ReserveBound(num_points, file_bytes, 14));
  for (int64_t p = 0; p < num_points; ++p) {
    ScenePoint point;
    for (int i = 0; i < 3; ++i) point.position[i] = NextDouble(r, "point position");
    for (int i = 0; i < 3; ++i) {
      point.color[i] = static_cast<uint8_t>(NextInt(r, "point colour", 0, 255));
    }
    const int64_t num_measurements = NextInt(r, "number of measurements", 0, INT32_MAX);
    for (int64_t m = 0; m < num_measurements; ++m) {
      const int64_t view = NextInt(r, "measurement image index", 0, num_cameras - 1);
      NextInt(r, "measurement feature index", INT32_MIN, INT64_MAX);
      const double x = NextDouble(r, "measurement x");
      const double y = NextDouble(r, "measurement y");
      if (!(std::abs(x) <= kMaxPixel && std::abs(y) <= kMaxPixel)) {
        r.Fail("measurement: pixel coordinate out of range");
      }
      if (chosen) {
        const Intrinsics& k = scene->views[view].intrinsics;
        point.observations.push_back({static_cast<int32_t>(view), static_cast<float>(x + k.cx),
                                      static_cast<float>(y + k.cy)});
      }
    }
    if (chosen) scene->points.push_back(std::move(point));
  }
}

}  // namespace

Scene ParseNvm(const std::string& name, std::string contents, int model_index,
               const ImageSizeLookup& image_size) {
  if (model_index < 0) throw InputError(name + ": NVM model index must be >= 0");
  const size_t file_bytes = contents.size();
  TextReader r(name, std::move(contents));
  bool r9t = false;
  const FixedK fixed = ParseHeader(r, &r9t);
  for (int model = 0;; ++model) {
    if (r.AtEnd()) {
      r.Fail("model " + std::to_string(model_index) + " requested but the file holds " +
             std::to_string(model) + " model(s)");
    }
    const int64_t num_cameras = NextInt(r, "number of cameras", 0, INT32_MAX);
    if (num_cameras == 0) {
      r.Fail("model " + std::to_string(model_index) + " requested but the file holds " +
             std::to_string(model) + " model(s)");
    }
    const bool chosen = model == model_index;
    std::vector<RawCamera> cameras;
    cameras.reserve(format::ReserveBound(num_cameras, file_bytes, 22));
    for (int64_t i = 0; i < num_cameras; ++i) cameras.push_back(ParseCamera(r, r9t));
    Scene scene;
    scene.source = name;
    if (chosen) {
      for (size_t i = 0; i < cameras.size(); ++i) {
        scene.views.push_back(ViewOfCamera(cameras[i], i, name, fixed, image_size));
      }
    }
    ParsePoints(r, num_cameras, chosen, file_bytes, &scene);
    if (chosen) {
      format::WarnDroppedDuplicates(name, format::SortAndDeduplicateObservations(&scene));
      return scene;
    }
  }
}

Scene ReadNvm(const std::string& path, const SceneReadOptions& options) {
  format::ImageLocator locator(path, options);
  Scene scene = ParseNvm(
      path, ReadFileToString(path), options.nvm_model_index, [&](const std::string& image) {
        return locator.RequireSize(image, "because NVM measures from the image centre");
      });
  locator.AttachImages(&scene);
  return scene;
}

void WriteNvm(const Scene& scene, const std::string& path, const SceneWriteOptions& options) {
  format::LossPolicy loss(path, "NVM", options.allow_lossy);
  bool all_centred = true;
  bool shared_k = true;
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    format::RequireTokenName(path, "NVM", i, v.name);
    const Intrinsics& k = v.intrinsics;
    if (!(k.fx == k.fy && k.cx == 0.5 * k.width && k.cy == 0.5 * k.height)) all_centred = false;
    const Intrinsics& k0 = scene.views[0].intrinsics;
    if (!(k.fx == k0.fx && k.fy == k0.fy && k.cx == k0.cx && k.cy == k0.cy)) shared_k = false;
  }
  const bool fixed_k = !all_centred && shared_k;
  if (!all_centred && !shared_k) {
    loss.Report(
        "per-view principal points off the image centre or fx != fy (written: the mean "
        "focal length, principal point at the centre)");
  }
  std::string out;
  if (fixed_k) {
    const Intrinsics& k0 = scene.views[0].intrinsics;
    out += fmt::format("NVM_V3 FixedK {} {} {} {} 0\n\n", FormatDouble(k0.fx), FormatDouble(k0.cx),
                       FormatDouble(k0.fy), FormatDouble(k0.cy));
  } else {
    out += "NVM_V3\n\n";
  }
  out += fmt::format("{}\n", scene.views.size());
  for (const View& v : scene.views) {
    const Intrinsics& k = v.intrinsics;
    double radial = 0;
    if (k.HasDistortion()) {
      if (k.p1 != 0 || k.p2 != 0) loss.Report("tangential distortion (p1, p2)");
      loss.Report("OpenCV radial distortion (fitted to VisualSFM's one-parameter model)");
      double r = 0;
      for (double x : {0.0, static_cast<double>(k.width)}) {
        for (double y : {0.0, static_cast<double>(k.height)}) {
          r = std::max(r, std::hypot((x - k.cx) / k.fx, (y - k.cy) / k.fy));
        }
      }
      radial = format::FitVisualSfmToOpenCv(k.k1, k.k2, k.k3, r);
    }
    const double f = fixed_k ? k.fx : 0.5 * (k.fx + k.fy);
    const Eigen::Vector4d q = QuaternionFromRotation(v.R);
    const Eigen::Vector3d c = v.Center();
    out += fmt::format("{} {} {} {} {} {} {} {} {} {} 0\n", v.name, FormatDouble(f),
                       FormatDouble(q[0]), FormatDouble(q[1]), FormatDouble(q[2]),
                       FormatDouble(q[3]), FormatDouble(c.x()), FormatDouble(c.y()),
                       FormatDouble(c.z()), FormatDouble(radial));
  }
  out += fmt::format("\n{}\n", scene.points.size());
  std::vector<int64_t> next_feature(scene.views.size(), 0);
  std::string measurements;
  for (const ScenePoint& p : scene.points) {
    measurements.clear();
    int count = 0;
    for (const Observation& o : p.observations) {
      double x = 0, y = 0;
      if (!format::ObservationPixel(scene, p, o, &loss, &x, &y)) continue;
      const Intrinsics& k = scene.views[o.view].intrinsics;
      const double ox = fixed_k ? k.cx : 0.5 * k.width;
      const double oy = fixed_k ? k.cy : 0.5 * k.height;
      measurements += fmt::format(" {} {} {} {}", o.view, next_feature[o.view]++,
                                  FormatDouble(x - ox), FormatDouble(y - oy));
      ++count;
    }
    out += fmt::format("{} {} {} {} {} {} {}{}\n", FormatDouble(p.position.x()),
                       FormatDouble(p.position.y()), FormatDouble(p.position.z()), p.color[0],
                       p.color[1], p.color[2], count, measurements);
  }
  out +=
      "\n0\n\n#the last part of NVM file points to the PLY files\n"
      "#the first number is the number of associated PLY files\n"
      "#each following number gives a model-index that has PLY\n0\n";
  WriteFileAtomically(
      path, [&](std::ostream& s) { s.write(out.data(), out.size()); }, false);
}

}  // namespace ms
