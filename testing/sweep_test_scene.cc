#include "testing/sweep_test_scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "mesh/float_robustness.h"
#include "mesh/visible_mesh.h"
#include "sweep/pyramid_geometry.h"

namespace ms {
namespace {

// Deterministic lattice hash -> [0, 1).
double LatticeValue(int64_t x, int64_t y, uint32_t seed) {
  uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ull ^
               static_cast<uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^ (uint64_t{seed} << 32);
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) / static_cast<double>(uint64_t{1} << 53);
}

double Smooth(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

double ValueNoise(double x, double y, uint32_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  const double sx = Smooth(x - fx), sy = Smooth(y - fy);
  const double a = LatticeValue(ix, iy, seed), b = LatticeValue(ix + 1, iy, seed);
  const double c = LatticeValue(ix, iy + 1, seed), d = LatticeValue(ix + 1, iy + 1, seed);
  return (a + sx * (b - a)) + sy * ((c + sx * (d - c)) - (a + sx * (b - a)));
}

// Multi-scale texture on the ground-plane coordinates, in [0, 1].
double Texture(double x, double y) {
  double sum = 0, norm = 0, wavelength = 0.05, amplitude = 1;
  for (int octave = 0; octave < 5; ++octave) {
    sum += amplitude * ValueNoise(x / wavelength, y / wavelength, 17 + octave);
    norm += amplitude;
    wavelength *= 2;
    amplitude *= 0.8;
  }
  // Stretch the (centre-heavy) sum so the texture uses most of [0, 1].
  return std::clamp(0.5 + 2.0 * (sum / norm - 0.5), 0.0, 1.0);
}

// The true surface's height at (x, y): the pyramid of apex height H on the ground plane.
double SurfaceHeight(double height, double x, double y) {
  return std::max(0.0, height * (1 - std::max(std::abs(x), std::abs(y))));
}

// First hit of the ray o + t d (t > 0) with the heightfield h(x, y) = max(0, H (1 - max(|x|,
// |y|))): the nearest hit on the five planes that lies on the surface.
bool CastRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double height,
             Eigen::Vector3d* hit) {
  double best = std::numeric_limits<double>::infinity();
  // Planes z = a x + b y + c: ground (0,0,0) and the four faces H(1 -+ x), H(1 -+ y).
  const double planes[5][3] = {{0, 0, 0},
                               {-height, 0, height},
                               {height, 0, height},
                               {0, -height, height},
                               {0, height, height}};
  for (const auto& p : planes) {
    const double denom = d.z() - p[0] * d.x() - p[1] * d.y();
    if (denom == 0) continue;
    const double t = (p[0] * o.x() + p[1] * o.y() + p[2] - o.z()) / denom;
    if (!(t > 0 && t < best)) continue;
    const Eigen::Vector3d q = o + t * d;
    const double surface = SurfaceHeight(height, q.x(), q.y());
    if (std::abs(q.z() - surface) <= 1e-9 * (1 + std::abs(q.z()))) best = t;
  }
  if (!std::isfinite(best)) return false;
  *hit = o + best * d;
  return true;
}

}  // namespace

View LookAtView(const Eigen::Vector3d& center, const Eigen::Vector3d& target, int width, int height,
                double focal_px) {
  const Eigen::Vector3d z = (target - center).normalized();
  const Eigen::Vector3d up(0, 1, 0);
  const Eigen::Vector3d y = -(up - up.dot(z) * z).normalized();  // image down = world -y
  const Eigen::Vector3d x = y.cross(z);
  View view;
  view.R.row(0) = x.transpose();
  view.R.row(1) = y.transpose();
  view.R.row(2) = z.transpose();
  view.SetCenter(center);
  view.intrinsics.width = width;
  view.intrinsics.height = height;
  view.intrinsics.fx = view.intrinsics.fy = focal_px;
  view.intrinsics.cx = width / 2.0;
  view.intrinsics.cy = height / 2.0;
  return view;
}

double PyramidScene::Height(double x, double y) const {
  return SurfaceHeight(pyramid_height, x, y);
}

double PyramidScene::Distance(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < truth.faces.size(); ++f) {
    const auto& face = truth.faces[f];
    const Eigen::Vector3d q = ClosestPointOnTriangle(
        p, {truth.vertices[face[0]], truth.vertices[face[1]], truth.vertices[face[2]]});
    best = std::min(best, (p - q).norm());
  }
  return best;
}

SweepJob MakePyramidSweepJob(const PyramidScene& scene, const Mesh& mesh) {
  SweepJob job;
  job.camera = scene.cameras[0];
  job.neighbours = {scene.cameras[1], scene.cameras[2]};
  job.mesh = ExtractVisibleMesh(mesh, job.camera.view).mesh;
  return job;
}

SweepJob MakeBenchmarkSweepJob(int width, int height) {
  PyramidSceneOptions options;
  options.width = width;
  options.height = height > 0 ? height : width * 3 / 4;
  options.supersample = 1;  // rendering cost only; the sweep does not care
  options.noise_stddev = 0.01;
  return MakePyramidSweepJob(MakePyramidScene(options), MakeFlatSquare(0.15, 1.3, 16));
}

Mesh MakeFlatSquare(double z, double half_size, int cells) {
  Mesh mesh;
  for (int r = 0; r <= cells; ++r) {
    for (int c = 0; c <= cells; ++c) {
      mesh.vertices.emplace_back(-half_size + 2 * half_size * c / cells,
                                 -half_size + 2 * half_size * r / cells, z);
    }
  }
  for (int r = 0; r < cells; ++r) {
    for (int c = 0; c < cells; ++c) {
      const int32_t a = r * (cells + 1) + c, b = a + 1, d = a + cells + 1, e = d + 1;
      mesh.faces.push_back({a, b, e});  // counter-clockwise seen from +z
      mesh.faces.push_back({a, e, d});
    }
  }
  return mesh;
}

PyramidScene MakePyramidScene(const PyramidSceneOptions& options) {
  PyramidScene scene;
  scene.pyramid_height = options.pyramid_height;
  const double h = options.pyramid_height;
  // Truth: apex, base corners, and a ground ring out to +-20 (counter-clockwise from above).
  // Not PyramidSides (sweep/pyramid_geometry.h): the same sides, but each face starts at the
  // apex here, and the sweep tests' numbers depend on the order.
  Mesh& t = scene.truth;
  t.vertices = {{0, 0, h}};
  for (const Eigen::Vector3d& corner : PyramidBaseCorners()) t.vertices.push_back(corner);
  for (const Eigen::Vector3d& corner : PyramidBaseCorners()) {
    t.vertices.push_back(20 * corner);  // the ground ring
  }
  t.faces = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1},  // pyramid sides
             {1, 5, 6}, {1, 6, 2}, {2, 6, 7}, {2, 7, 3},  // ground ring
             {3, 7, 8}, {3, 8, 4}, {4, 8, 5}, {4, 5, 1}};

  const double focal = options.focal_px * options.width / 160.0;
  const Eigen::Vector3d target(0, 0, 0.1);
  const Eigen::Vector3d centers[3] = {{0.05, -0.1, 2.6}, {0.6, 0.05, 2.5}, {-0.55, 0.15, 2.7}};
  const int ss = std::max(1, options.supersample);
  for (int i = 0; i < 3; ++i) {
    SweepCamera camera;
    camera.id = i;
    camera.view = LookAtView(centers[i], target, options.width, options.height, focal);
    camera.view.name = "pyramid_" + std::to_string(i);
    camera.image.create(options.height, options.width, CV_32F);
    const Eigen::Vector3d origin = camera.view.Center();
    for (int row = 0; row < options.height; ++row) {
      for (int col = 0; col < options.width; ++col) {
        double sum = 0;
        for (int sy = 0; sy < ss; ++sy) {
          for (int sx = 0; sx < ss; ++sx) {
            const Eigen::Vector2d pixel(col + (sx + 0.5) / ss, row + (sy + 0.5) / ss);
            Eigen::Vector3d hit;
            const double value = CastRay(origin, camera.view.PixelRay(pixel), h, &hit)
                                     ? Texture(hit.x(), hit.y())
                                     : 0.5;
            sum += 0.5 + options.texture_contrast * (value - 0.5);
          }
        }
        camera.image.at<float>(row, col) = static_cast<float>(sum / (ss * ss));
      }
    }
    if (options.noise_stddev > 0) {
      cv::Mat noise(camera.image.size(), CV_32F);
      cv::RNG rng(1000 + i);
      rng.fill(noise, cv::RNG::NORMAL, 0.0, options.noise_stddev);
      camera.image += noise;
    }
    scene.cameras.push_back(std::move(camera));
  }
  return scene;
}

SweepJob MakeSmallSweepJob(const PyramidScene& scene, const Mesh& mesh) {
  SweepJob job = MakePyramidSweepJob(scene, mesh);
  job.options.gaussian_sigma_px = 4;
  job.options.tile_size_px = 10;
  return job;
}

SweepJob MakeTinyValidSweepJob() {
  PyramidSceneOptions options;
  options.width = 40;
  options.height = 30;
  options.supersample = 1;
  return MakeSmallSweepJob(MakePyramidScene(options), MakeFlatSquare(0.15, 1.3, 2));
}

const PyramidScene& NoisyPyramidScene() {
  static const PyramidScene scene = [] {
    PyramidSceneOptions options;
    options.noise_stddev = 0.01;
    return MakePyramidScene(options);
  }();
  return scene;
}

Mesh TruthWithOccluder(const PyramidScene& scene) {
  Mesh mesh = scene.truth;
  const int32_t base = static_cast<int32_t>(mesh.vertices.size());
  mesh.vertices.insert(
      mesh.vertices.end(),
      {{0.35, -0.35, 0.9}, {0.75, -0.35, 0.9}, {0.75, 0.05, 0.9}, {0.35, 0.05, 0.9}});
  mesh.faces.push_back({base, base + 1, base + 2});  // counter-clockwise from above
  mesh.faces.push_back({base, base + 2, base + 3});
  return mesh;
}

cv::Mat BlurredNoiseImage(int width, int height, uint64_t seed) {
  cv::Mat image(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 1.5);
  return image;
}

}  // namespace ms
