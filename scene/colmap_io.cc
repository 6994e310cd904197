#include "scene/colmap_io.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <unordered_map>

#include "base/binary_reader.h"
#include "base/error.h"
#include "base/file_util.h"
#include "base/text_reader.h"
#include "scene/format_util.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

using format::Quote;

constexpr int64_t kMaxSide = int64_t{1} << 20;
using format::kMaxPixel;

struct ModelInfo {
  const char* name;
  int num_params;
};
// COLMAP's camera model ids are the indices into this table.
constexpr ModelInfo kModels[] = {{"SIMPLE_PINHOLE", 3},
                                 {"PINHOLE", 4},
                                 {"SIMPLE_RADIAL", 4},
                                 {"RADIAL", 5},
                                 {"OPENCV", 8},
                                 {"OPENCV_FISHEYE", 8},
                                 {"FULL_OPENCV", 12},
                                 {"FOV", 5},
                                 {"SIMPLE_RADIAL_FISHEYE", 4},
                                 {"RADIAL_FISHEYE", 5},
                                 {"THIN_PRISM_FISHEYE", 12},
                                 {"RAD_TAN_THIN_PRISM_FISHEYE", 16}};
constexpr int kNumModels = sizeof(kModels) / sizeof(kModels[0]);
enum ModelId { kSimplePinhole = 0, kPinhole, kSimpleRadial, kRadial, kOpenCv, kFullOpenCv = 6 };

int ModelIdFromName(std::string_view name) {
  for (int i = 0; i < kNumModels; ++i) {
    if (name == kModels[i].name) return i;
  }
  return -1;
}

struct Camera {
  uint32_t id = 0;
  int model = 0;
  int width = 0, height = 0;
  std::vector<double> params;
  uint64_t where = 0;  // line (text) or byte offset (binary)
};

struct Image {
  uint32_t id = 0;
  std::array<double, 4> q{};
  std::array<double, 3> t{};
  uint32_t camera_id = 0;
  std::string name;
  std::vector<std::array<float, 2>> points2d;
  uint64_t where = 0;
};

struct Point {
  uint64_t id = 0;
  Eigen::Vector3d xyz;
  std::array<uint8_t, 3> rgb{};
  std::vector<std::pair<uint32_t, uint32_t>> track;  // (image id, point2D index)
  uint64_t where = 0;
};

std::string Where(const std::string& file, uint64_t where, bool binary) {
  return binary ? file + ": byte " + std::to_string(where) : file + ":" + std::to_string(where);
}

float CheckedPixel(double value, const std::function<void(const std::string&)>& fail) {
  if (!(std::abs(value) <= kMaxPixel))
    fail("pixel coordinate " + format::FormatDouble(value) + " is out of range");
  return static_cast<float>(value);
}

// ---- text -----------------------------------------------------------------------------------

std::vector<Camera> ParseCamerasText(const std::string& name, std::string contents) {
  TextReader r(name, std::move(contents));
  std::vector<Camera> cameras;
  std::string_view line;
  while (r.NextDataLine(&line)) {
    const auto f = format::SplitFieldsAtMost(r, line, 4 + 16, "camera line");
    if (f.size() < 4) r.Fail("camera line needs CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    Camera c;
    c.where = r.line_number();
    c.id = static_cast<uint32_t>(format::ParseInt(r, f[0], "CAMERA_ID", 0, UINT32_MAX - 1));
    c.model = ModelIdFromName(f[1]);
    if (c.model < 0) r.Fail("MODEL: unknown camera model " + Quote(f[1]));
    c.width = static_cast<int>(format::ParseInt(r, f[2], "WIDTH", 1, kMaxSide));
    c.height = static_cast<int>(format::ParseInt(r, f[3], "HEIGHT", 1, kMaxSide));
    const size_t expected = kModels[c.model].num_params;
    if (f.size() - 4 != expected) {
      r.Fail(std::string("PARAMS: model ") + kModels[c.model].name + " has " +
             std::to_string(expected) + " parameters, the line has " +
             std::to_string(f.size() - 4));
    }
    for (size_t i = 4; i < f.size(); ++i)
      c.params.push_back(format::ParseDouble(r, f[i], "PARAMS"));
    cameras.push_back(std::move(c));
  }
  return cameras;
}

std::vector<Image> ParseImagesText(const std::string& name, std::string contents) {
  TextReader r(name, std::move(contents));
  std::vector<Image> images;
  std::string_view line;
  while (r.NextDataLine(&line)) {
    const auto f = format::SplitFieldsAtMost(r, line, 10, "image line");
    if (f.size() != 10) {
      r.Fail("image line needs IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 fields), got " +
             std::to_string(f.size()));
    }
    Image image;
    image.where = r.line_number();
    image.id = static_cast<uint32_t>(format::ParseInt(r, f[0], "IMAGE_ID", 0, UINT32_MAX - 1));
    static const char* const kQ[] = {"QW", "QX", "QY", "QZ"};
    static const char* const kT[] = {"TX", "TY", "TZ"};
    for (int i = 0; i < 4; ++i) image.q[i] = format::ParseDouble(r, f[1 + i], kQ[i]);
    for (int i = 0; i < 3; ++i) image.t[i] = format::ParseDouble(r, f[5 + i], kT[i]);
    image.camera_id =
        static_cast<uint32_t>(format::ParseInt(r, f[8], "CAMERA_ID", 0, UINT32_MAX - 1));
    image.name = std::string(f[9]);
    // The POINTS2D line follows directly and may be empty (an image without features).
    std::string_view points_line;
    if (r.NextLine(&points_line)) {
      const size_t count = format::CountFields(points_line);
      if (count % 3 != 0) {
        r.Fail("POINTS2D: " + std::to_string(count) +
               " values is not a multiple of 3 (X Y POINT3D_ID)");
      }
      image.points2d.reserve(count / 3);
      const auto fail = [&](const std::string& m) { r.Fail("POINTS2D: " + m); };
      format::FieldCursor cursor(points_line);
      std::string_view x_text, y_text, id_text;
      while (cursor.Next(&x_text) && cursor.Next(&y_text) && cursor.Next(&id_text)) {
        const float x = CheckedPixel(format::ParseDouble(r, x_text, "POINTS2D X"), fail);
        const float y = CheckedPixel(format::ParseDouble(r, y_text, "POINTS2D Y"), fail);
        format::ParseInt(r, id_text, "POINTS2D POINT3D_ID", -1, INT64_MAX);
        image.points2d.push_back({x, y});
      }
    }
    images.push_back(std::move(image));
  }
  return images;
}

std::vector<Point> ParsePointsText(const std::string& name, std::string contents) {
  TextReader r(name, std::move(contents));
  std::vector<Point> points;
  std::string_view line;
  while (r.NextDataLine(&line)) {
    const size_t count = format::CountFields(line);
    if (count < 8 || (count - 8) % 2 != 0) {
      r.Fail(
          "point line needs POINT3D_ID X Y Z R G B ERROR and (IMAGE_ID POINT2D_IDX) pairs, got " +
          std::to_string(count) + " fields");
    }
    format::FieldCursor cursor(line);
    std::array<std::string_view, 8> f;
    for (std::string_view& field : f) cursor.Next(&field);
    Point p;
    p.where = r.line_number();
    p.id = static_cast<uint64_t>(format::ParseInt(r, f[0], "POINT3D_ID", 0, INT64_MAX));
    p.xyz = {format::ParseDouble(r, f[1], "X"), format::ParseDouble(r, f[2], "Y"),
             format::ParseDouble(r, f[3], "Z")};
    static const char* const kRgb[] = {"R", "G", "B"};
    for (int i = 0; i < 3; ++i) {
      p.rgb[i] = static_cast<uint8_t>(format::ParseInt(r, f[4 + i], kRgb[i], 0, 255));
    }
    format::ParseDouble(r, f[7], "ERROR");
    p.track.reserve((count - 8) / 2);
    std::string_view image_text, index_text;
    while (cursor.Next(&image_text) && cursor.Next(&index_text)) {
      const auto image_id = format::ParseInt(r, image_text, "TRACK IMAGE_ID", 0, UINT32_MAX - 1);
      const auto index = format::ParseInt(r, index_text, "TRACK POINT2D_IDX", 0, UINT32_MAX);
      p.track.emplace_back(static_cast<uint32_t>(image_id), static_cast<uint32_t>(index));
    }
    points.push_back(std::move(p));
  }
  return points;
}

// ---- binary ---------------------------------------------------------------------------------

std::vector<Camera> ParseCamerasBinary(const std::string& name, const std::string& data) {
  BinaryReader b(name, data.data(), data.size());
  const uint64_t n = b.Read<uint64_t>("number of cameras");
  b.CheckCount(n, 4 + 4 + 8 + 8, "number of cameras");
  std::vector<Camera> cameras;
  cameras.reserve(format::ReserveBound(n, data.size(), 24));
  for (uint64_t i = 0; i < n; ++i) {
    Camera c;
    c.where = b.position();
    c.id = b.Read<uint32_t>("camera_id");
    const int32_t model = b.Read<int32_t>("model_id");
    if (model < 0 || model >= kNumModels)
      b.Fail("model_id: unknown camera model id " + std::to_string(model));
    c.model = model;
    const uint64_t width = b.Read<uint64_t>("width");
    const uint64_t height = b.Read<uint64_t>("height");
    if (width < 1 || width > kMaxSide || height < 1 || height > kMaxSide) {
      b.Fail("camera " + std::to_string(c.id) + ": size " + std::to_string(width) + "x" +
             std::to_string(height) + " is out of range [1, " + std::to_string(kMaxSide) + "]");
    }
    c.width = static_cast<int>(width);
    c.height = static_cast<int>(height);
    for (int k = 0; k < kModels[model].num_params; ++k)
      c.params.push_back(b.ReadFiniteDouble("params"));
    cameras.push_back(std::move(c));
  }
  if (!b.AtEnd()) b.Fail("unexpected data after the last camera");
  return cameras;
}

std::vector<Image> ParseImagesBinary(const std::string& name, const std::string& data) {
  BinaryReader b(name, data.data(), data.size());
  const uint64_t n = b.Read<uint64_t>("number of images");
  b.CheckCount(n, 4 + 32 + 24 + 4 + 1 + 8, "number of images");
  std::vector<Image> images;
  images.reserve(format::ReserveBound(n, data.size(), 73));
  for (uint64_t i = 0; i < n; ++i) {
    Image image;
    image.where = b.position();
    image.id = b.Read<uint32_t>("image_id");
    for (double& q : image.q) q = b.ReadFiniteDouble("qvec");
    for (double& t : image.t) t = b.ReadFiniteDouble("tvec");
    image.camera_id = b.Read<uint32_t>("camera_id");
    image.name = b.ReadCString("name");
    const uint64_t num_points = b.Read<uint64_t>("number of points2D");
    b.CheckCount(num_points, 24, "number of points2D");
    image.points2d.reserve(format::ReserveBound(num_points, data.size(), 24));
    const auto fail = [&](const std::string& m) { b.Fail("points2D: " + m); };
    for (uint64_t k = 0; k < num_points; ++k) {
      const float x = CheckedPixel(b.ReadFiniteDouble("points2D x"), fail);
      const float y = CheckedPixel(b.ReadFiniteDouble("points2D y"), fail);
      b.Read<uint64_t>("points2D point3D_id");
      image.points2d.push_back({x, y});
    }
    images.push_back(std::move(image));
  }
  if (!b.AtEnd()) b.Fail("unexpected data after the last image");
  return images;
}

std::vector<Point> ParsePointsBinary(const std::string& name, const std::string& data) {
  BinaryReader b(name, data.data(), data.size());
  const uint64_t n = b.Read<uint64_t>("number of points3D");
  b.CheckCount(n, 8 + 24 + 3 + 8 + 8, "number of points3D");
  std::vector<Point> points;
  points.reserve(format::ReserveBound(n, data.size(), 51));
  for (uint64_t i = 0; i < n; ++i) {
    Point p;
    p.where = b.position();
    p.id = b.Read<uint64_t>("point3D_id");
    p.xyz.x() = b.ReadFiniteDouble("xyz");
    p.xyz.y() = b.ReadFiniteDouble("xyz");
    p.xyz.z() = b.ReadFiniteDouble("xyz");
    for (uint8_t& c : p.rgb) c = b.Read<uint8_t>("rgb");
    b.Read<double>("error");
    const uint64_t length = b.Read<uint64_t>("track length");
    b.CheckCount(length, 8, "track length");
    p.track.reserve(format::ReserveBound(length, data.size(), 8));
    for (uint64_t k = 0; k < length; ++k) {
      const uint32_t image_id = b.Read<uint32_t>("track image_id");
      const uint32_t index = b.Read<uint32_t>("track point2D_idx");
      p.track.emplace_back(image_id, index);
    }
    points.push_back(std::move(p));
  }
  if (!b.AtEnd()) b.Fail("unexpected data after the last point");
  return points;
}

// ---- model -> scene -------------------------------------------------------------------------

Intrinsics ToIntrinsics(const Camera& c, const std::string& where) {
  Intrinsics k;
  k.width = c.width;
  k.height = c.height;
  const std::vector<double>& p = c.params;
  switch (c.model) {
    case kSimplePinhole:
      k.fx = k.fy = p[0];
      k.cx = p[1];
      k.cy = p[2];
      break;
    case kPinhole:
      k.fx = p[0];
      k.fy = p[1];
      k.cx = p[2];
      k.cy = p[3];
      break;
    case kSimpleRadial:
      k.fx = k.fy = p[0];
      k.cx = p[1];
      k.cy = p[2];
      k.k1 = p[3];
      break;
    case kRadial:
      k.fx = k.fy = p[0];
      k.cx = p[1];
      k.cy = p[2];
      k.k1 = p[3];
      k.k2 = p[4];
      break;
    case kOpenCv:
    case kFullOpenCv:
      k.fx = p[0];
      k.fy = p[1];
      k.cx = p[2];
      k.cy = p[3];
      k.k1 = p[4];
      k.k2 = p[5];
      k.p1 = p[6];
      k.p2 = p[7];
      if (c.model == kFullOpenCv) {
        k.k3 = p[8];
        if (p[9] != 0 || p[10] != 0 || p[11] != 0) {
          throw InputError(where + ": camera " + std::to_string(c.id) +
                           ": FULL_OPENCV with rational terms k4, k5, k6 != 0 is not supported "
                           "(only OpenCV's k1, k2, p1, p2, k3)");
        }
      }
      break;
    default:
      throw InputError(where + ": camera " + std::to_string(c.id) + ": camera model " +
                       kModels[c.model].name +
                       " is not supported (supported: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, "
                       "RADIAL, OPENCV, FULL_OPENCV without k4..k6)");
  }
  return k;
}

template <typename T, typename Id>
void RequireUniqueIds(const std::vector<T>& items, Id T::*id, const std::string& file, bool binary,
                      const char* what) {
  std::vector<const T*> sorted;
  sorted.reserve(items.size());
  for (const T& item : items) sorted.push_back(&item);
  std::sort(sorted.begin(), sorted.end(), [&](const T* a, const T* b) { return a->*id < b->*id; });
  for (size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i]->*id == sorted[i - 1]->*id) {
      throw InputError(Where(file, std::max(sorted[i]->where, sorted[i - 1]->where), binary) +
                       ": " + what + " id " + std::to_string(sorted[i]->*id) + " appears twice");
    }
  }
}

Scene ToScene(const ColmapFiles& files, bool binary, const std::vector<Camera>& cameras,
              std::vector<Image> images, std::vector<Point> points) {
  RequireUniqueIds(cameras, &Camera::id, files.cameras_name, binary, "camera");
  RequireUniqueIds(images, &Image::id, files.images_name, binary, "image");
  RequireUniqueIds(points, &Point::id, files.points_name, binary, "point");
  std::unordered_map<uint32_t, const Camera*> camera_by_id;
  for (const Camera& c : cameras) camera_by_id[c.id] = &c;
  std::sort(images.begin(), images.end(),
            [](const Image& a, const Image& b) { return a.id < b.id; });
  std::sort(points.begin(), points.end(),
            [](const Point& a, const Point& b) { return a.id < b.id; });

  Scene scene;
  std::unordered_map<uint32_t, int32_t> view_by_image_id;
  scene.views.reserve(images.size());
  for (const Image& image : images) {
    const std::string where = Where(files.images_name, image.where, binary);
    const auto cam = camera_by_id.find(image.camera_id);
    if (cam == camera_by_id.end()) {
      throw InputError(where + ": image " + std::to_string(image.id) + ": camera " +
                       std::to_string(image.camera_id) + " is not in " + files.cameras_name);
    }
    View view;
    view.name = image.name;
    view.intrinsics =
        ToIntrinsics(*cam->second, Where(files.cameras_name, cam->second->where, binary));
    const Eigen::Vector4d q(image.q[0], image.q[1], image.q[2], image.q[3]);
    if (!(q.norm() > 1e-9)) {
      throw InputError(where + ": image " + std::to_string(image.id) +
                       ": quaternion has zero length");
    }
    view.R = RotationFromQuaternion(q[0], q[1], q[2], q[3]);
    view.t = {image.t[0], image.t[1], image.t[2]};
    view_by_image_id[image.id] = static_cast<int32_t>(scene.views.size());
    scene.views.push_back(std::move(view));
  }
  scene.points.reserve(points.size());
  for (const Point& p : points) {
    ScenePoint point;
    point.position = p.xyz;
    point.color = p.rgb;
    point.observations.reserve(p.track.size());
    for (const auto& [image_id, index] : p.track) {
      const auto view = view_by_image_id.find(image_id);
      if (view == view_by_image_id.end()) {
        throw InputError(Where(files.points_name, p.where, binary) + ": point " +
                         std::to_string(p.id) + ": track refers to image " +
                         std::to_string(image_id) + ", which is not in " + files.images_name);
      }
      const Image& image = images[view->second];
      if (index >= image.points2d.size()) {
        throw InputError(Where(files.points_name, p.where, binary) + ": point " +
                         std::to_string(p.id) + ": track refers to POINTS2D entry " +
                         std::to_string(index) + " of image " + std::to_string(image_id) +
                         ", which has " + std::to_string(image.points2d.size()));
      }
      point.observations.push_back(
          {view->second, image.points2d[index][0], image.points2d[index][1]});
    }
    scene.points.push_back(std::move(point));
  }
  scene.source = files.points_name;
  format::WarnDroppedDuplicates(files.points_name, format::SortAndDeduplicateObservations(&scene));
  return scene;
}

// ---- writing --------------------------------------------------------------------------------

struct CameraOut {
  int model;
  std::vector<double> params;
  const Intrinsics* intrinsics;
};

CameraOut ChooseModel(const Intrinsics& k) {
  const bool square = k.fx == k.fy;
  if (!k.HasDistortion()) {
    if (square) return {kSimplePinhole, {k.fx, k.cx, k.cy}, &k};
    return {kPinhole, {k.fx, k.fy, k.cx, k.cy}, &k};
  }
  if (square && k.p1 == 0 && k.p2 == 0 && k.k3 == 0) {
    if (k.k2 == 0) return {kSimpleRadial, {k.fx, k.cx, k.cy, k.k1}, &k};
    return {kRadial, {k.fx, k.cx, k.cy, k.k1, k.k2}, &k};
  }
  if (k.k3 == 0) return {kOpenCv, {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2}, &k};
  return {kFullOpenCv, {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3, 0, 0, 0}, &k};
}

struct Point2dOut {
  double x, y;
  int64_t point_id;
};

struct ModelOut {
  std::vector<CameraOut> cameras;                                  // camera id = index + 1
  std::vector<int> camera_of_view;                                 // index into cameras
  std::vector<std::vector<Point2dOut>> points2d;                   // per view
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> tracks;  // per point
  std::vector<double> errors;  // per point, mean reprojection error
};

ModelOut BuildModel(const Scene& scene, const std::string& path, bool binary,
                    const SceneWriteOptions& options) {
  format::LossPolicy loss(path, binary ? "colmap-binary" : "colmap-text", options.allow_lossy);
  ModelOut out;
  out.camera_of_view.resize(scene.views.size());
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    if (binary) {
      if (v.name.empty() || v.name.find('\0') != std::string::npos) {
        throw InputError(path + ": view " + std::to_string(i) +
                         ": image name is empty or has a NUL");
      }
    } else {
      format::RequireTokenName(path, "COLMAP text", i, v.name);
    }
    int found = -1;
    for (size_t c = 0; c < out.cameras.size(); ++c) {
      if (*out.cameras[c].intrinsics == v.intrinsics) {
        found = static_cast<int>(c);
        break;
      }
    }
    if (found < 0) {
      found = static_cast<int>(out.cameras.size());
      out.cameras.push_back(ChooseModel(v.intrinsics));
    }
    out.camera_of_view[i] = found;
  }
  out.points2d.resize(scene.views.size());
  out.tracks.resize(scene.points.size());
  out.errors.resize(scene.points.size(), 0.0);
  for (size_t p = 0; p < scene.points.size(); ++p) {
    const ScenePoint& point = scene.points[p];
    double error_sum = 0;
    int error_count = 0;
    for (const Observation& o : point.observations) {
      double x = 0, y = 0;
      if (!format::ObservationPixel(scene, point, o, &loss, &x, &y)) continue;
      auto& list = out.points2d[o.view];
      out.tracks[p].emplace_back(static_cast<uint32_t>(o.view + 1),
                                 static_cast<uint32_t>(list.size()));
      list.push_back({x, y, static_cast<int64_t>(p + 1)});
      Eigen::Vector2d projected;
      if (scene.views[o.view].Project(point.position, &projected)) {
        error_sum += (projected - Eigen::Vector2d(x, y)).norm();
        ++error_count;
      }
    }
    out.errors[p] = error_count > 0 ? error_sum / error_count : 0.0;
  }
  return out;
}

void WriteBuffer(const fs::path& path, const std::string& data) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
  });
}

void WriteText(const Scene& scene, const ModelOut& m, const fs::path& dir) {
  using format::FormatDouble;
  std::string cameras = fmt::format(
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: {}\n",
      m.cameras.size());
  for (size_t c = 0; c < m.cameras.size(); ++c) {
    const CameraOut& cam = m.cameras[c];
    cameras += fmt::format("{} {} {} {}", c + 1, kModels[cam.model].name, cam.intrinsics->width,
                           cam.intrinsics->height);
    for (double p : cam.params) cameras += " " + FormatDouble(p);
    cameras += "\n";
  }
  WriteBuffer(dir / "cameras.txt", cameras);

  size_t num_points2d = 0;
  for (const auto& list : m.points2d) num_points2d += list.size();
  std::string images = fmt::format(
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: {}, mean observations per image: {}\n",
      scene.views.size(),
      scene.views.empty() ? 0.0 : static_cast<double>(num_points2d) / scene.views.size());
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    const Eigen::Vector4d q = QuaternionFromRotation(v.R);
    images += fmt::format("{} {} {} {} {} {} {} {} {} {}\n", i + 1, FormatDouble(q[0]),
                          FormatDouble(q[1]), FormatDouble(q[2]), FormatDouble(q[3]),
                          FormatDouble(v.t.x()), FormatDouble(v.t.y()), FormatDouble(v.t.z()),
                          m.camera_of_view[i] + 1, v.name);
    bool first = true;
    for (const Point2dOut& p : m.points2d[i]) {
      if (!first) images += ' ';
      first = false;
      images += fmt::format("{} {} {}", FormatDouble(p.x), FormatDouble(p.y), p.point_id);
    }
    images += "\n";
  }
  WriteBuffer(dir / "images.txt", images);

  size_t track_sum = 0;
  for (const auto& t : m.tracks) track_sum += t.size();
  std::string points = fmt::format(
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: {}, mean track length: {}\n",
      scene.points.size(),
      scene.points.empty() ? 0.0 : static_cast<double>(track_sum) / scene.points.size());
  for (size_t p = 0; p < scene.points.size(); ++p) {
    const ScenePoint& point = scene.points[p];
    points +=
        fmt::format("{} {} {} {} {} {} {} {}", p + 1, FormatDouble(point.position.x()),
                    FormatDouble(point.position.y()), FormatDouble(point.position.z()),
                    point.color[0], point.color[1], point.color[2], FormatDouble(m.errors[p]));
    for (const auto& [image_id, index] : m.tracks[p])
      points += fmt::format(" {} {}", image_id, index);
    points += "\n";
  }
  WriteBuffer(dir / "points3D.txt", points);
}

template <typename T>
void Put(std::string* out, T value) {
  out->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

void WriteBinary(const Scene& scene, const ModelOut& m, const fs::path& dir) {
  std::string cameras;
  Put<uint64_t>(&cameras, m.cameras.size());
  for (size_t c = 0; c < m.cameras.size(); ++c) {
    const CameraOut& cam = m.cameras[c];
    Put<uint32_t>(&cameras, static_cast<uint32_t>(c + 1));
    Put<int32_t>(&cameras, cam.model);
    Put<uint64_t>(&cameras, static_cast<uint64_t>(cam.intrinsics->width));
    Put<uint64_t>(&cameras, static_cast<uint64_t>(cam.intrinsics->height));
    for (double p : cam.params) Put<double>(&cameras, p);
  }
  WriteBuffer(dir / "cameras.bin", cameras);

  std::string images;
  Put<uint64_t>(&images, scene.views.size());
  for (size_t i = 0; i < scene.views.size(); ++i) {
    const View& v = scene.views[i];
    Put<uint32_t>(&images, static_cast<uint32_t>(i + 1));
    const Eigen::Vector4d q = QuaternionFromRotation(v.R);
    for (int k = 0; k < 4; ++k) Put<double>(&images, q[k]);
    for (int k = 0; k < 3; ++k) Put<double>(&images, v.t[k]);
    Put<uint32_t>(&images, static_cast<uint32_t>(m.camera_of_view[i] + 1));
    images.append(v.name);
    images.push_back('\0');
    Put<uint64_t>(&images, m.points2d[i].size());
    for (const Point2dOut& p : m.points2d[i]) {
      Put<double>(&images, p.x);
      Put<double>(&images, p.y);
      Put<uint64_t>(&images, static_cast<uint64_t>(p.point_id));
    }
  }
  WriteBuffer(dir / "images.bin", images);

  std::string points;
  Put<uint64_t>(&points, scene.points.size());
  for (size_t p = 0; p < scene.points.size(); ++p) {
    const ScenePoint& point = scene.points[p];
    Put<uint64_t>(&points, p + 1);
    for (int k = 0; k < 3; ++k) Put<double>(&points, point.position[k]);
    for (int k = 0; k < 3; ++k) Put<uint8_t>(&points, point.color[k]);
    Put<double>(&points, m.errors[p]);
    Put<uint64_t>(&points, m.tracks[p].size());
    for (const auto& [image_id, index] : m.tracks[p]) {
      Put<uint32_t>(&points, image_id);
      Put<uint32_t>(&points, index);
    }
  }
  WriteBuffer(dir / "points3D.bin", points);
}

}  // namespace

Scene ParseColmapModel(ColmapFiles files, bool binary) {
  if (binary) {
    auto cameras = ParseCamerasBinary(files.cameras_name, files.cameras);
    auto images = ParseImagesBinary(files.images_name, files.images);
    auto points = ParsePointsBinary(files.points_name, files.points);
    return ToScene(files, binary, cameras, std::move(images), std::move(points));
  }
  auto cameras = ParseCamerasText(files.cameras_name, std::move(files.cameras));
  auto images = ParseImagesText(files.images_name, std::move(files.images));
  auto points = ParsePointsText(files.points_name, std::move(files.points));
  return ToScene(files, binary, cameras, std::move(images), std::move(points));
}

std::string FindColmapModelDir(const std::string& path) {
  std::error_code ec;
  for (const fs::path& dir :
       {fs::path(path), fs::path(path) / "sparse", fs::path(path) / "sparse" / "0"}) {
    if (fs::is_regular_file(dir / "cameras.bin", ec) ||
        fs::is_regular_file(dir / "cameras.txt", ec)) {
      return dir.string();
    }
  }
  return "";
}

bool ColmapModelIsBinary(const std::string& model_dir) {
  std::error_code ec;
  return fs::is_regular_file(fs::path(model_dir) / "cameras.bin", ec);
}

Scene ReadColmapModel(const std::string& path, bool binary, const SceneReadOptions& options) {
  const std::string dir = FindColmapModelDir(path);
  if (dir.empty()) {
    throw InputError(path +
                     ": no COLMAP model (cameras.txt or cameras.bin) here, in sparse/ or "
                     "in sparse/0/");
  }
  const std::string ext = binary ? ".bin" : ".txt";
  ColmapFiles files;
  files.cameras_name = (fs::path(dir) / ("cameras" + ext)).string();
  files.images_name = (fs::path(dir) / ("images" + ext)).string();
  files.points_name = (fs::path(dir) / ("points3D" + ext)).string();
  files.cameras = ReadFileToString(files.cameras_name);
  files.images = ReadFileToString(files.images_name);
  files.points = ReadFileToString(files.points_name);
  Scene scene = ParseColmapModel(std::move(files), binary);
  scene.source = dir;
  format::ImageLocator(dir, options).AttachImages(&scene);
  return scene;
}

void WriteColmapModel(const Scene& scene, const std::string& dir, bool binary,
                      const SceneWriteOptions& options) {
  const ModelOut model = BuildModel(scene, dir, binary, options);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir + ": cannot create directory: " + ec.message());
  if (binary) {
    WriteBinary(scene, model, dir);
  } else {
    WriteText(scene, model, dir);
  }
}

}  // namespace ms
