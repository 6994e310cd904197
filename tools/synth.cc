#include "tools/synth.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <unordered_map>

#include "base/error.h"
#include "base/file_util.h"
#include "base/log.h"
#include "gl/mesh_renderer.h"
#include "mesh/mesh_io.h"
#include "mesh/ray_caster.h"
#include "scene/scene_io.h"
#include "tools/plot.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

// SplitMix64: independent, reproducible streams from one seed (sampling, noise, view k, ...).
uint64_t StreamSeed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

enum Stream : uint64_t { kSampling = 1, kPointNoise = 2, kImageNoise = 1000 };

SynthOptions ResolveDefaults(const SynthOptions& options, SynthSceneKind kind) {
  SynthOptions o = options;
  const bool city = kind == SynthSceneKind::kCity;
  if (o.views == 0) {
    o.views = kind == SynthSceneKind::kBlob ? 24 : city ? 60 : 16;
  }
  if (o.width == 0) o.width = city ? 1024 : 800;
  if (o.height == 0) o.height = city ? 768 : 600;
  if (o.points == 0) {
    o.points = kind == SynthSceneKind::kBlob ? 3000 : city ? 40 * o.views : 4;
  }
  if (kind == SynthSceneKind::kPyramidDown || kind == SynthSceneKind::kPyramidUp) o.points = 4;
  return o;
}

// Which views see a point: in front, inside the image, within reach, facing the camera closer
// than the grazing limit, and not occluded (ray cast against the ground truth).
class VisibilityTester {
 public:
  VisibilityTester(const std::vector<View>& views, const Mesh& mesh, double max_distance,
                   double max_grazing_deg)
      : views_(views),
        caster_(mesh),
        max_distance_(max_distance),
        min_cos_(std::cos(max_grazing_deg * M_PI / 180)) {
    BoundingBox box;
    for (const Eigen::Vector3d& v : mesh.vertices) box.Extend(v);
    scale_ = std::max(box.Diagonal(), 1e-9);
    for (const View& v : views_) centers_.push_back(v.Center());
    if (max_distance_ > 0) {
      for (size_t i = 0; i < views_.size(); ++i) grid_[Key(Cell(centers_[i]))].push_back(i);
    }
  }

  std::vector<Observation> Observe(const Eigen::Vector3d& p, const Eigen::Vector3d& normal) const {
    std::vector<Observation> out;
    auto consider = [&](size_t i) {
      const View& view = views_[i];
      const Eigen::Vector3d to_camera = centers_[i] - p;
      const double distance = to_camera.norm();
      if (max_distance_ > 0 && distance > max_distance_) return;
      if (normal.dot(to_camera) < min_cos_ * distance) return;
      Eigen::Vector2d pixel;
      if (!view.Project(p, &pixel)) return;
      if (!(pixel.x() >= 0.5 && pixel.y() >= 0.5 && pixel.x() <= view.intrinsics.width - 0.5 &&
            pixel.y() <= view.intrinsics.height - 0.5)) {
        return;
      }
      if (caster_.Occluded(centers_[i], p, 1e-6 * distance + 1e-9 * scale_)) return;
      out.push_back(
          {static_cast<int32_t>(i), static_cast<float>(pixel.x()), static_cast<float>(pixel.y())});
    };
    if (max_distance_ > 0) {
      const Eigen::Vector3i c = Cell(p);
      std::vector<size_t> candidates;
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dz = -1; dz <= 1; ++dz) {
            auto it = grid_.find(Key(c + Eigen::Vector3i(dx, dy, dz)));
            if (it != grid_.end())
              candidates.insert(candidates.end(), it->second.begin(), it->second.end());
          }
        }
      }
      std::sort(candidates.begin(), candidates.end());
      for (size_t i : candidates) consider(i);
    } else {
      for (size_t i = 0; i < views_.size(); ++i) consider(i);
    }
    return out;
  }

 private:
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const {
    return (p / max_distance_).array().floor().cast<int>();
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    return (int64_t{c.x()} & 0x1FFFFF) | ((int64_t{c.y()} & 0x1FFFFF) << 21) |
           ((int64_t{c.z()} & 0x1FFFFF) << 42);
  }
  const std::vector<View>& views_;
  RayCaster caster_;
  double max_distance_;
  double min_cos_;
  double scale_ = 1;
  std::vector<Eigen::Vector3d> centers_;
  std::unordered_map<int64_t, std::vector<size_t>> grid_;
};

// Area-weighted random points on the mesh, kept when enough views see them.
void SamplePoints(const SynthGeometry& g, const SynthOptions& o, SynthDataset* d) {
  const Mesh& mesh = g.mesh;
  VisibilityTester tester(g.views, mesh, g.max_view_distance, o.max_grazing_deg);
  std::vector<double> cumulative(mesh.faces.size());
  double total = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) cumulative[f] = total += mesh.FaceArea(f);
  std::mt19937_64 rng(StreamSeed(o.seed, kSampling));
  std::uniform_real_distribution<double> uniform(0, 1);
  const int64_t max_candidates = int64_t{50} * o.points;
  int64_t candidates = 0;
  Progress progress("sampling sparse points", o.points);
  while (static_cast<int>(d->exact_points.size()) < o.points && candidates < max_candidates) {
    ++candidates;
    const double pick = uniform(rng) * total;
    const size_t f = std::min<size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(),
        mesh.faces.size() - 1);
    double u = uniform(rng), v = uniform(rng);
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    const auto& face = mesh.faces[f];
    const Eigen::Vector3d p = mesh.vertices[face[0]] +
                              u * (mesh.vertices[face[1]] - mesh.vertices[face[0]]) +
                              v * (mesh.vertices[face[2]] - mesh.vertices[face[0]]);
    std::vector<Observation> seen = tester.Observe(p, mesh.FaceNormal(f));
    if (static_cast<int>(seen.size()) < o.min_track) continue;
    ScenePoint point;
    point.position = p;
    point.observations = std::move(seen);
    d->scene.points.push_back(std::move(point));
    d->exact_points.push_back(p);
    d->point_faces.push_back(static_cast<int32_t>(f));
    progress.Update(static_cast<int64_t>(d->exact_points.size()));
  }
  progress.Finish(static_cast<int64_t>(d->exact_points.size()));
  if (static_cast<int>(d->exact_points.size()) < o.points) {
    spdlog::warn("synth: only {} of {} sparse points are seen by {}+ views after {} candidates",
                 d->exact_points.size(), o.points, o.min_track, candidates);
  }
}

void AddFixedPoints(const SynthGeometry& g, SynthDataset* d) {
  for (const Eigen::Vector3d& p : g.fixed_points) {
    ScenePoint point;
    point.position = p;
    for (size_t i = 0; i < g.views.size(); ++i) {
      Eigen::Vector2d pixel;
      if (!g.views[i].Project(p, &pixel) || pixel.x() < 0 || pixel.y() < 0 ||
          pixel.x() > g.views[i].intrinsics.width || pixel.y() > g.views[i].intrinsics.height) {
        throw InternalError(fmt::format("synth: base corner outside view {}", i));
      }
      point.observations.push_back(
          {static_cast<int32_t>(i), static_cast<float>(pixel.x()), static_cast<float>(pixel.y())});
    }
    d->scene.points.push_back(std::move(point));
    d->exact_points.push_back(p);
    d->point_faces.push_back(-1);
  }
}

std::vector<cv::Mat> LoadPhotos(const std::vector<std::string>& paths) {
  std::vector<cv::Mat> photos;
  for (const std::string& path : ListPhotos(paths)) {
    cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
    if (image.empty()) throw InputError(path + ": cannot read as an image (--texture-photos)");
    // Large photographs: keep ~1k pixels across, enough for a 1024^2 texture layer.
    const int side = std::min(image.cols, image.rows);
    const cv::Rect square((image.cols - side) / 2, (image.rows - side) / 2, side, side);
    photos.push_back(image(square).clone());
  }
  return photos;
}

void RenderImages(const SynthGeometry& g, const SynthOptions& o, const gl::GlContext& context,
                  SynthDataset* d) {
  gl::SurfaceTexture texture = g.texture;
  texture.seed = static_cast<uint32_t>(StreamSeed(o.seed, 3) & 0xFFFFFFFFu);
  texture.photos = LoadPhotos(o.texture_photos);
  if (!texture.photos.empty()) {
    for (size_t m = 0; m < texture.materials.size(); ++m) {
      texture.materials[m].photo = static_cast<int>(m % texture.photos.size());
      texture.materials[m].photo_weight = 0.75f;
    }
  }
  gl::SurfaceRenderer renderer(context, g.mesh, texture);
  gl::SurfaceRenderOptions render;
  render.supersampling = o.supersampling;
  Progress progress("rendering images", static_cast<int64_t>(g.views.size()));
  for (size_t i = 0; i < g.views.size(); ++i) {
    cv::Mat image = renderer.Render(g.views[i], render);
    if (o.image_noise > 0) {
      cv::Mat noise(image.size(), CV_32FC3);
      cv::RNG rng(StreamSeed(o.seed, kImageNoise + i));
      rng.fill(noise, cv::RNG::NORMAL, 0, o.image_noise);
      cv::Mat noisy;
      image.convertTo(noisy, CV_32FC3);
      noisy += noise;
      noisy.convertTo(image, CV_8UC3);  // rounds and saturates to [0, 255]
    }
    d->images.push_back(std::move(image));
    progress.Update(static_cast<int64_t>(i + 1));
  }
  progress.Finish(static_cast<int64_t>(g.views.size()));
}

void ColorPoints(const SynthGeometry& g, SynthDataset* d) {
  for (size_t i = 0; i < d->scene.points.size(); ++i) {
    ScenePoint& point = d->scene.points[i];
    if (!d->images.empty() && !point.observations.empty()) {
      const Observation& o = point.observations.front();
      const cv::Mat& image = d->images[o.view];
      const int col = std::clamp(static_cast<int>(o.x), 0, image.cols - 1);
      const int row = std::clamp(static_cast<int>(o.y), 0, image.rows - 1);
      const cv::Vec3b bgr = image.at<cv::Vec3b>(row, col);
      point.color = {bgr[2], bgr[1], bgr[0]};
    } else {
      const int f = d->point_faces[i];
      const int m = (f < 0 || g.texture.face_material.empty()) ? 0 : g.texture.face_material[f];
      const Eigen::Vector3f c = g.texture.materials[m].color * 255.0f;
      point.color = {static_cast<uint8_t>(c.x()), static_cast<uint8_t>(c.y()),
                     static_cast<uint8_t>(c.z())};
    }
  }
}

}  // namespace

void SynthOptions::Check() const {
  ParseSynthScene(scene);
  if (views < 0 || views > 1000000) throw InputError("synth.views: must be in [1, 1000000]");
  if (views == 1) throw InputError("synth.views: at least 2 views are needed");
  if (width < 0 || width > 16384 || height < 0 || height > 16384) {
    throw InputError("synth.width/height: must be in [16, 16384]");
  }
  if ((width > 0 && width < 16) || (height > 0 && height < 16)) {
    throw InputError("synth.width/height: must be in [16, 16384]");
  }
  if (!(image_noise >= 0 && image_noise <= 255)) {
    throw InputError("synth.image_noise: must be in [0, 255] grey levels");
  }
  if (!(point_noise >= 0) || !std::isfinite(point_noise)) {
    throw InputError("synth.point_noise: must be >= 0");
  }
  if (points < 0 || points > 100000000) throw InputError("synth.points: must be in [0, 1e8]");
  if (min_track < 1) throw InputError("synth.min_track: must be >= 1");
  if (!(max_grazing_deg > 0 && max_grazing_deg <= 90)) {
    throw InputError("synth.max_grazing_deg: must be in (0, 90]");
  }
  if (supersampling < 1 || supersampling > 8) {
    throw InputError("synth.supersampling: must be in [1, 8]");
  }
}

std::vector<std::string> ListPhotos(const std::vector<std::string>& paths) {
  std::vector<std::string> files;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      std::vector<std::string> found;
      for (const auto& entry : fs::directory_iterator(path, ec)) {
        std::string ext = entry.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
        if (entry.is_regular_file() && (ext == ".jpg" || ext == ".jpeg" || ext == ".png")) {
          found.push_back(entry.path().string());
        }
      }
      if (found.empty()) throw InputError(path + ": no .jpg/.png photos in this directory");
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else {
      RequireFile(path, "photo");
      files.push_back(path);
    }
  }
  return files;
}

SynthDataset MakeSynthDataset(const SynthOptions& options, const gl::GlContext* context) {
  options.Check();
  const SynthSceneKind kind = ParseSynthScene(options.scene);
  const SynthOptions o = ResolveDefaults(options, kind);
  if (o.render_images && context == nullptr) {
    throw InternalError("MakeSynthDataset: rendering images needs a GL context");
  }
  SynthDataset d;
  d.scene_name = SynthSceneName(kind);
  d.options = o;
  Timer timer;
  const SynthGeometry g = MakeSynthGeometry(kind, {o.views, o.width, o.height, o.seed});
  d.ground_truth = g.mesh;
  d.initial_mesh = g.initial_mesh;
  d.scene.views = g.views;
  d.scene.source = "synth " + d.scene_name;
  d.evaluation_view = g.evaluation_view;
  d.seconds_geometry = timer.Seconds();

  timer.Restart();
  if (!g.fixed_points.empty()) {
    AddFixedPoints(g, &d);
  } else {
    SamplePoints(g, o, &d);
  }
  if (o.point_noise > 0) {
    std::mt19937_64 rng(StreamSeed(o.seed, kPointNoise));
    std::normal_distribution<double> noise(0, o.point_noise);
    for (ScenePoint& p : d.scene.points) {
      for (int c = 0; c < 3; ++c) p.position[c] += noise(rng);
    }
  }
  d.seconds_points = timer.Seconds();

  timer.Restart();
  if (o.render_images) RenderImages(g, o, *context, &d);
  d.seconds_images = timer.Seconds();
  ColorPoints(g, &d);
  d.scene.NormalizeObservations();
  d.scene.Validate();
  spdlog::info("synth {}: {}", d.scene_name, d.scene.Summary());
  return d;
}

void WriteSynthDataset(const SynthDataset& d, const std::string& directory) {
  const fs::path dir(directory);
  std::error_code ec;
  fs::create_directories(d.images.empty() ? dir : dir / "images", ec);
  if (ec) throw InputError(directory + ": cannot create the dataset directory: " + ec.message());
  Scene scene = d.scene;
  // Absolute, so that scene.h5 works from any working directory (a Slurm job's, a worker's).
  const fs::path images = fs::absolute(dir) / "images";
  for (View& view : scene.views) view.image_path = (images / view.name).string();
  if (!d.images.empty()) {
    Progress progress("writing images", static_cast<int64_t>(d.images.size()));
    for (size_t i = 0; i < d.images.size(); ++i) {
      WritePng(scene.views[i].image_path, d.images[i]);
      progress.Update(static_cast<int64_t>(i + 1));
    }
    progress.Finish(static_cast<int64_t>(d.images.size()));
  }
  WriteMesh(d.ground_truth, (dir / "gt.ply").string());
  if (!d.initial_mesh.faces.empty()) WriteMesh(d.initial_mesh, (dir / "initial.ply").string());
  PointCloud cloud;
  for (const ScenePoint& p : scene.points) {
    cloud.points.push_back(p.position);
    cloud.colors.push_back(p.color);
  }
  WritePointCloud(cloud, (dir / "sparse.ply").string());

  const SynthOptions& o = d.options;
  nlohmann::json json = {{"generator", "manisweep synth"},
                         {"scene", d.scene_name},
                         {"seed", o.seed},
                         {"views", scene.views.size()},
                         {"width", o.width},
                         {"height", o.height},
                         {"points", scene.points.size()},
                         {"observations", scene.NumObservations()},
                         {"image_noise", o.image_noise},
                         {"point_noise", o.point_noise},
                         {"min_track", o.min_track},
                         {"max_grazing_deg", o.max_grazing_deg},
                         {"supersampling", o.supersampling},
                         {"images", !d.images.empty()},
                         {"texture_photos", ListPhotos(o.texture_photos)},
                         {"evaluation_view", d.evaluation_view},
                         {"files",
                          {{"ground_truth", "gt.ply"},
                           {"initial_mesh", d.initial_mesh.faces.empty() ? "" : "initial.ply"},
                           {"sparse_points", "sparse.ply"},
                           {"colmap", "sparse"},
                           {"scene", "scene.h5"},
                           {"images", "images"}}},
                         {"seconds",
                          {{"geometry", d.seconds_geometry},
                           {"points", d.seconds_points},
                           {"images", d.seconds_images}}}};
  WriteFileAtomically(
      dir / "synth.json", [&](std::ostream& out) { out << json.dump(2) << "\n"; },
      /*binary=*/false);
  // Scene files last: the formats are the project's importers' (scene/scene_io.h).
  WriteScene(scene, (dir / "sparse").string(), SceneFormat::kColmapText);
  WriteScene(scene, (dir / "scene.h5").string(), SceneFormat::kManisweepH5);
}

}  // namespace ms
