#include "tools/synth_scenes.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>

#include "base/check.h"
#include "base/error.h"

namespace ms {
namespace {

std::string ImageName(int index) { return fmt::format("{:04d}.png", index); }

Intrinsics CenteredIntrinsics(int width, int height, double focal) {
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = focal;
  k.cx = 0.5 * width;
  k.cy = 0.5 * height;
  return k;
}

// Appends a quad a,b,c,d (counter-clockwise seen from outside) as two triangles.
void AddQuad(Mesh* mesh, std::vector<int32_t>* materials, int material, const Eigen::Vector3d& a,
             const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  const int32_t base = static_cast<int32_t>(mesh->vertices.size());
  mesh->vertices.insert(mesh->vertices.end(), {a, b, c, d});
  mesh->faces.push_back({base, base + 1, base + 2});
  mesh->faces.push_back({base, base + 2, base + 3});
  materials->push_back(material);
  materials->push_back(material);
}

// Icosphere: 20 * 4^level faces, counter-clockwise seen from outside.
Mesh Icosphere(int level) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  Mesh mesh;
  for (const Eigen::Vector3d& v :
       {Eigen::Vector3d(-1, t, 0), Eigen::Vector3d(1, t, 0), Eigen::Vector3d(-1, -t, 0),
        Eigen::Vector3d(1, -t, 0), Eigen::Vector3d(0, -1, t), Eigen::Vector3d(0, 1, t),
        Eigen::Vector3d(0, -1, -t), Eigen::Vector3d(0, 1, -t), Eigen::Vector3d(t, 0, -1),
        Eigen::Vector3d(t, 0, 1), Eigen::Vector3d(-t, 0, -1), Eigen::Vector3d(-t, 0, 1)}) {
    mesh.vertices.push_back(v.normalized());
  }
  mesh.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int32_t, int32_t>, int32_t> midpoints;
    auto midpoint = [&](int32_t a, int32_t b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      mesh.vertices.push_back((mesh.vertices[a] + mesh.vertices[b]).normalized());
      const int32_t index = static_cast<int32_t>(mesh.vertices.size()) - 1;
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<std::array<int32_t, 3>> faces;
    for (const auto& f : mesh.faces) {
      const int32_t ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      faces.push_back({f[0], ab, ca});
      faces.push_back({f[1], bc, ab});
      faces.push_back({f[2], ca, bc});
      faces.push_back({ab, bc, ca});
    }
    mesh.faces = std::move(faces);
  }
  return mesh;
}

}  // namespace

SynthSceneKind ParseSynthScene(const std::string& name) {
  if (name == "pyramid-down") return SynthSceneKind::kPyramidDown;
  if (name == "pyramid-up") return SynthSceneKind::kPyramidUp;
  if (name == "blob") return SynthSceneKind::kBlob;
  if (name == "city") return SynthSceneKind::kCity;
  throw InputError("unknown synthetic scene '" + name +
                   "' (use pyramid-down, pyramid-up, blob or city)");
}

std::string SynthSceneName(SynthSceneKind kind) {
  switch (kind) {
    case SynthSceneKind::kPyramidDown:
      return "pyramid-down";
    case SynthSceneKind::kPyramidUp:
      return "pyramid-up";
    case SynthSceneKind::kBlob:
      return "blob";
    case SynthSceneKind::kCity:
      return "city";
  }
  return "unknown";
}

View LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target, const Eigen::Vector3d& up,
            const Intrinsics& intrinsics) {
  const Eigen::Vector3d z = (target - center).normalized();
  Eigen::Vector3d x = z.cross(up);
  if (x.norm() < 1e-9) x = z.cross(Eigen::Vector3d::UnitY());
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  View view;
  view.intrinsics = intrinsics;
  view.R.row(0) = x.transpose();
  view.R.row(1) = y.transpose();
  view.R.row(2) = z.transpose();
  view.SetCenter(center);
  return view;
}

double FitFocalLength(const std::vector<View>& views, const std::vector<Eigen::Vector3d>& points,
                      double margin) {
  double focal = INFINITY;
  for (const View& view : views) {
    const double half_w = 0.5 * view.intrinsics.width * (1 - margin);
    const double half_h = 0.5 * view.intrinsics.height * (1 - margin);
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3d c = view.ToCamera(p);
      MS_CHECK(c.z() > 0) << "FitFocalLength: a point lies behind a camera";
      const double ax = std::abs(c.x() / c.z()), ay = std::abs(c.y() / c.z());
      if (ax > 0) focal = std::min(focal, half_w / ax);
      if (ay > 0) focal = std::min(focal, half_h / ay);
    }
  }
  return focal;
}

SynthGeometry MakePyramidScene(bool apex_up, const SynthLayout& layout) {
  SynthGeometry g;
  const std::array<Eigen::Vector3d, 4> corners = PyramidBaseCorners();
  const Eigen::Vector3d apex(0, 0, apex_up ? kPyramidHeight : -kPyramidHeight);
  // Four triangles, counter-clockwise seen from above, where the cameras are.
  g.mesh = PyramidSides(apex.z());
  g.initial_mesh = PyramidBaseSquare();
  g.fixed_points.assign(corners.begin(), corners.end());

  gl::SurfaceMaterial material;
  material.color = {0.62f, 0.56f, 0.48f};
  material.noise_period = 0.5f;
  material.noise_contrast = 0.7f;
  material.photo_period = 1.0f;
  g.texture.materials = {material};

  // A Fibonacci spiral on the cap from 88 to 70 degrees of elevation, 1.2 m from the centre:
  // neighbours ~10 degrees apart, every view sees the whole pyramid. View 0 is almost vertical.
  // At 1.2 m the base square's mean relative error from view 0 matches the paper's Table 1
  // (docs/reference/evaluation.md), i.e. the paper's viewing distance.
  const double distance = 1.2;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  const int n = layout.views;
  for (int i = 0; i < n; ++i) {
    const double s = n > 1 ? static_cast<double>(i) / (n - 1) : 0;
    const double elevation = (88 - 18 * std::sqrt(s)) * M_PI / 180;
    const double azimuth = -M_PI / 2 + golden * i;
    const Eigen::Vector3d center =
        distance * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                   std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    View view = LookAt(center, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY(),
                       CenteredIntrinsics(layout.width, layout.height, 1));
    view.name = ImageName(i);
    g.views.push_back(view);
  }
  // Each view zooms to fit the pyramid (a shared focal length would leave the oblique views'
  // images mostly empty at this short distance).
  std::vector<Eigen::Vector3d> extent(corners.begin(), corners.end());
  extent.push_back(apex);
  for (View& view : g.views) {
    view.intrinsics.fx = view.intrinsics.fy = FitFocalLength({view}, extent, 0.06);
  }
  g.max_view_distance = 0;
  return g;
}

SynthGeometry MakeBlobScene(const SynthLayout& layout) {
  SynthGeometry g;
  g.mesh = Icosphere(5);
  std::mt19937_64 rng(layout.seed * 0x9E3779B97F4A7C15ull + 0xB10B);
  std::uniform_real_distribution<double> uniform(0, 1);
  struct Bump {
    Eigen::Vector3d direction;
    double amplitude, width;
  };
  std::vector<Bump> bumps;
  for (int k = 0; k < 14; ++k) {
    const double z = 2 * uniform(rng) - 1, phi = 2 * M_PI * uniform(rng);
    const double r = std::sqrt(1 - z * z);
    bumps.push_back({Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z),
                     -0.12 + 0.32 * uniform(rng), 0.25 + 0.35 * uniform(rng)});
  }
  for (Eigen::Vector3d& v : g.mesh.vertices) {
    double radius = 1 + 0.05 * std::sin(3 * v.x()) * std::cos(2 * v.y() + 1.3 * v.z());
    for (const Bump& b : bumps) {
      const double angle = std::acos(std::clamp(v.dot(b.direction), -1.0, 1.0));
      radius += b.amplitude * std::exp(-0.5 * angle * angle / (b.width * b.width));
    }
    v *= radius;
  }
  gl::SurfaceMaterial material;
  material.color = {0.66f, 0.58f, 0.47f};
  material.noise_period = 0.6f;
  material.noise_contrast = 0.7f;
  material.photo_period = 1.5f;
  g.texture.materials = {material};

  // Two interleaved rings at 10 and 35 degrees of elevation, 3.5 from the centre.
  const int n = layout.views;
  for (int i = 0; i < n; ++i) {
    const double azimuth = 2 * M_PI * i / n;
    const double elevation = (i % 2 == 0 ? 10.0 : 35.0) * M_PI / 180;
    const Eigen::Vector3d center =
        3.5 * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    View view = LookAt(center, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(),
                       CenteredIntrinsics(layout.width, layout.height, 1));
    view.name = ImageName(i);
    g.views.push_back(view);
  }
  const double focal = FitFocalLength(g.views, g.mesh.vertices, 0.08);
  for (View& view : g.views) view.intrinsics.fx = view.intrinsics.fy = focal;
  return g;
}

SynthGeometry MakeCityScene(const SynthLayout& layout) {
  SynthGeometry g;
  std::mt19937_64 rng(layout.seed * 0x9E3779B97F4A7C15ull + 0xC17);
  std::uniform_real_distribution<double> uniform(0, 1);
  auto between = [&](double lo, double hi) { return lo + (hi - lo) * uniform(rng); };

  // Materials: 0 asphalt, 1 pavement, 2..5 facades, 6 roofs.
  auto material = [](Eigen::Vector3f color, float period, float contrast, float windows) {
    gl::SurfaceMaterial m;
    m.color = color;
    m.noise_period = period;
    m.noise_contrast = contrast;
    m.photo_period = 4 * period;
    m.window_spacing = windows;
    m.floor_height = 3.2f;
    return m;
  };
  g.texture.materials = {material({0.22f, 0.22f, 0.23f}, 3.0f, 0.6f, 0),
                         material({0.52f, 0.5f, 0.47f}, 1.5f, 0.5f, 0),
                         material({0.78f, 0.68f, 0.52f}, 2.0f, 0.55f, 3.0f),
                         material({0.62f, 0.42f, 0.36f}, 2.0f, 0.55f, 2.6f),
                         material({0.72f, 0.72f, 0.66f}, 2.0f, 0.55f, 3.4f),
                         material({0.5f, 0.56f, 0.62f}, 2.0f, 0.55f, 2.2f),
                         material({0.36f, 0.22f, 0.19f}, 3.0f, 0.5f, 0)};
  std::vector<int32_t>& face_material = g.texture.face_material;

  const int stations = (layout.views + 1) / 2;
  const double spacing = 1.5;
  const double length = (stations - 1) * spacing;
  const double x0 = -40, x1 = length + 40;
  const double street = 6, facade_line = 9, ground_half = 40;

  // Ground in 10 m tiles; the street (|y| < 6) asphalt, the rest pavement.
  const std::vector<double> ys = {-ground_half, -street, street, ground_half};
  for (double x = x0; x < x1; x += 10) {
    const double xe = std::min(x + 10, x1);
    for (size_t j = 0; j + 1 < ys.size(); ++j) {
      const int m = (j == 1) ? 0 : 1;
      AddQuad(&g.mesh, &face_material, m, {x, ys[j], 0}, {xe, ys[j], 0}, {xe, ys[j + 1], 0},
              {x, ys[j + 1], 0});
    }
  }
  // Buildings on both sides; a side street every 60-100 m.
  for (int side : {-1, 1}) {
    double x = x0 + between(0, 5);
    double next_side_street = x + between(60, 100);
    while (x < x1 - 5) {
      if (x > next_side_street) {
        x += 10;
        next_side_street = x + between(60, 100);
        continue;
      }
      const double width = between(8, 22);
      const double xe = std::min(x + width, x1);
      const double setback = uniform(rng) < 0.5 ? 0 : between(0, 1.5);
      const double depth = between(10, 18), height = between(6, 28);
      const double y_front = side * (facade_line + setback);
      const double y_back = side * (facade_line + setback + depth);
      const int m = 2 + static_cast<int>(uniform(rng) * 4) % 4;
      // Corners of the footprint, counter-clockwise seen from above.
      Eigen::Vector3d p[4] = {{x, std::min(y_front, y_back), 0},
                              {xe, std::min(y_front, y_back), 0},
                              {xe, std::max(y_front, y_back), 0},
                              {x, std::max(y_front, y_back), 0}};
      const Eigen::Vector3d up(0, 0, height);
      for (int i = 0; i < 4; ++i) {  // walls, outward normals
        const Eigen::Vector3d& a = p[i];
        const Eigen::Vector3d& b = p[(i + 1) % 4];
        AddQuad(&g.mesh, &face_material, m, a, b, b + up, a + up);
      }
      AddQuad(&g.mesh, &face_material, 6, p[0] + up, p[1] + up, p[2] + up, p[3] + up);
      x = xe + (uniform(rng) < 0.6 ? 0.0 : between(1, 4));
    }
  }
  // Cameras: per station one looking forward-left, one forward-right, 1.7 m high, pitched up.
  const double focal = 0.5 * layout.width / std::tan(35 * M_PI / 180);
  for (int i = 0; i < layout.views; ++i) {
    const int station = i / 2;
    const int side = i % 2 == 0 ? 1 : -1;
    // Jitter per station so both cameras of a pair share a centre offset.
    std::mt19937_64 station_rng(layout.seed * 0x9E3779B97F4A7C15ull + 7919 * station + 1);
    std::uniform_real_distribution<double> jitter(-1, 1);
    const Eigen::Vector3d center(station * spacing, 1.5 * jitter(station_rng),
                                 1.7 + 0.1 * jitter(station_rng));
    const double yaw = side * (60 + 5 * jitter(station_rng)) * M_PI / 180;
    const double pitch = 8 * M_PI / 180;
    const Eigen::Vector3d direction(std::cos(pitch) * std::cos(yaw),
                                    std::cos(pitch) * std::sin(yaw), std::sin(pitch));
    View view = LookAt(center, center + direction, Eigen::Vector3d::UnitZ(),
                       CenteredIntrinsics(layout.width, layout.height, focal));
    view.name = ImageName(i);
    g.views.push_back(view);
  }
  g.max_view_distance = 50;
  g.texture.up = Eigen::Vector3f::UnitZ();
  return g;
}

SynthGeometry MakeSynthGeometry(SynthSceneKind kind, const SynthLayout& layout) {
  switch (kind) {
    case SynthSceneKind::kPyramidDown:
      return MakePyramidScene(false, layout);
    case SynthSceneKind::kPyramidUp:
      return MakePyramidScene(true, layout);
    case SynthSceneKind::kBlob:
      return MakeBlobScene(layout);
    case SynthSceneKind::kCity:
      return MakeCityScene(layout);
  }
  throw InternalError("unknown synthetic scene kind");
}

}  // namespace ms
