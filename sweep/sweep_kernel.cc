#include "sweep/sweep_kernel.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tuple>

#include "base/check.h"
#include "base/error.h"
#include "mesh/visible_mesh.h"
#include "scene/camera.h"
#include "sweep/image_noise.h"
#include "sweep/vector_clones.h"

namespace ms {
namespace {

std::string CameraName(const SweepCamera& camera, const char* role) {
  return fmt::format("{} {} ('{}')", role, camera.id, camera.view.name);
}

void CheckCamera(const SweepCamera& camera, const std::string& job, const char* role) {
  const std::string who = job + ": " + CameraName(camera, role);
  const Intrinsics& k = camera.view.intrinsics;
  if (!(k.width > 0 && k.height > 0)) throw InputError(who + ": image size must be positive");
  if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && k.fx > 0 && k.fy > 0)) {
    throw InputError(who + ": focal length must be finite and positive");
  }
  if (!(std::isfinite(k.cx) && std::isfinite(k.cy))) {
    throw InputError(who + ": principal point not finite");
  }
  if (k.HasDistortion()) {
    throw InputError(who +
                     ": view has lens distortion; the sweep takes undistorted images and "
                     "pinhole views (undistort them first)");
  }
  if (!camera.view.t.allFinite() || !IsRotation(camera.view.R, 1e-4)) {
    throw InputError(who + ": pose is not a finite proper rotation and translation");
  }
  const cv::Mat& image = camera.image;
  if (image.empty()) throw InputError(who + ": image missing");
  if (image.type() != CV_32FC1) {
    throw InputError(who + ": image must be single-channel float (CV_32FC1), got type " +
                     std::to_string(image.type()));
  }
  if (image.cols != k.width || image.rows != k.height) {
    throw InputError(fmt::format("{}: image is {}x{} but the view's intrinsics say {}x{}", who,
                                 image.cols, image.rows, k.width, k.height));
  }
  if (!cv::checkRange(image, /*quiet=*/true)) {
    throw InputError(who + ": image has non-finite pixels");
  }
}

}  // namespace

std::string SweepStats::Summary() const {
  return fmt::format(
      "{}x{} (level {}), noise {:.2f} grey levels (smoothed: sigma {:.2f} px), alpha {:.4g}, {} "
      "offsets x {} neighbours, {} tiles, {:.3g} hypotheses ({:.3g} valid) in {:.3f} s ({:.3g}/s; "
      "prepare {:.3f}, raster {:.3f}, reproject {:.3f}, ncc {:.3f}, reduce {:.3f})",
      image_width, image_height, pyramid_level, image_noise, smoothing_px, alpha, num_offsets,
      num_neighbours, tiles_x * tiles_y, static_cast<double>(hypotheses),
      static_cast<double>(valid_hypotheses), total_s, total_s > 0 ? hypotheses / total_s : 0.0,
      prepare_s, raster_s, reproject_s, ncc_s, reduce_s);
}

void CheckSweepJob(const SweepJob& job) {
  job.options.Check();
  const std::string name = fmt::format("sweep job for camera {}", job.camera.id);
  CheckCamera(job.camera, name, "camera");
  if (job.neighbours.empty()) throw InputError(name + ": no neighbour cameras");
  const Eigen::Vector3d center = job.camera.view.Center();
  for (const SweepCamera& n : job.neighbours) {
    CheckCamera(n, name, "neighbour");
    if (n.id == job.camera.id) throw InputError(name + ": the camera is its own neighbour");
    const double baseline = (n.view.Center() - center).norm();
    if (!(baseline > 1e-12 * std::max(1.0, center.norm()))) {
      throw InputError(name + ": " + CameraName(n, "neighbour") +
                       " is at the camera's centre (no parallax)");
    }
  }
  const Mesh& mesh = job.mesh;
  if (mesh.faces.empty()) throw InputError(name + ": mesh has no faces");
  const int64_t num_vertices = static_cast<int64_t>(mesh.vertices.size());
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!mesh.vertices[v].allFinite()) {
      throw InputError(fmt::format("{}: mesh vertex {} is not finite", name, v));
    }
  }
  bool any_in_front = false;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    for (int32_t v : face) {
      if (v < 0 || v >= num_vertices) {
        throw InputError(
            fmt::format("{}: mesh face {} refers to vertex {} of {}", name, f, v, num_vertices));
      }
    }
    if (!any_in_front) {
      any_in_front = TriangleInFrustum(job.camera.view, mesh.vertices[face[0]],
                                       mesh.vertices[face[1]], mesh.vertices[face[2]]);
    }
  }
  if (!any_in_front) {
    throw InputError(name +
                     ": no face of the mesh is in front of the camera inside its image "
                     "(camera outside the scene, or the wrong mesh)");
  }
}

std::vector<int> SweepOffsets(int num_offsets) {
  const int k_max = (num_offsets - 1) / 2;
  std::vector<int> offsets;
  for (int k = -k_max; k <= k_max; ++k) offsets.push_back(k);
  return offsets;
}

Eigen::Vector3d SweepVertex(const Eigen::Vector3d& v, const Eigen::Vector3d& n,
                            const Eigen::Vector3d& c, double alpha_k) {
  const Eigen::Vector3d ray = v - c;
  const double length = ray.norm();
  if (!(length > 0)) return v;
  const Eigen::Vector3d d = ray / length;
  return v + alpha_k * std::abs(n.dot(d)) * d;
}

TileGrid TileGrid::Make(int width, int height, double tile_size_px) {
  TileGrid grid;
  grid.width = width;
  grid.height = height;
  grid.tiles_x =
      std::max(1, static_cast<int>(std::lround(static_cast<double>(width) / tile_size_px)));
  grid.tiles_y =
      std::max(1, static_cast<int>(std::lround(static_cast<double>(height) / tile_size_px)));
  grid.tiles_x = std::min(grid.tiles_x, std::max(1, width));
  grid.tiles_y = std::min(grid.tiles_y, std::max(1, height));
  return grid;
}

TileGrid TileGrid::ForOptions(int width, int height, const SweepOptions& options) {
  const double size = options.tiles_across > 0
                          ? static_cast<double>(std::max(width, height)) / options.tiles_across
                          : options.tile_size_px;
  return Make(width, height, size);
}

cv::Mat GaussianWindow(double sigma_px) {
  const int radius = static_cast<int>(std::ceil(3 * sigma_px));
  cv::Mat window(2 * radius + 1, 1, CV_32F);
  double sum = 0;
  std::vector<double> w(2 * radius + 1);
  for (int i = -radius; i <= radius; ++i) {
    w[i + radius] = std::exp(-0.5 * i * i / (sigma_px * sigma_px));
    sum += w[i + radius];
  }
  for (int i = 0; i <= 2 * radius; ++i) window.at<float>(i) = static_cast<float>(w[i] / sum);
  return window;
}

double AutoSweepAlpha(const View& camera, const std::vector<View>& neighbours, const Mesh& mesh,
                      double parallax_px, double median_depth) {
  const Eigen::Vector3d center = camera.Center();
  // Up to ~4096 vertices, evenly strided: the median needs no more.
  const size_t stride = std::max<size_t>(1, mesh.vertices.size() / 4096);
  std::vector<double> rates;
  for (size_t i = 0; i < mesh.vertices.size(); i += stride) {
    const Eigen::Vector3d& X = mesh.vertices[i];
    if (!(camera.ToCamera(X).z() > 0)) continue;
    const Eigen::Vector3d d = (X - center).normalized();
    for (const View& n : neighbours) {
      const Eigen::Vector3d x = n.ToCamera(X);
      if (!(x.z() > 0)) continue;
      const Eigen::Vector3d dx = n.R * d;  // d(x)/ds
      const double z2 = x.z() * x.z();
      const double du = n.intrinsics.fx * (dx.x() * x.z() - x.x() * dx.z()) / z2;
      const double dv = n.intrinsics.fy * (dx.y() * x.z() - x.y() * dx.z()) / z2;
      rates.push_back(std::hypot(du, dv));
    }
  }
  const double max_alpha = 0.02 * median_depth;
  if (rates.empty()) return max_alpha;
  auto mid = rates.begin() + rates.size() / 2;
  std::nth_element(rates.begin(), mid, rates.end());
  const double rate = *mid;
  if (!(rate > 0)) return max_alpha;
  return std::min(parallax_px / rate, max_alpha);
}

SweepStats PreparedSweepStats(const PreparedSweep& prep) {
  SweepStats stats;
  stats.image_width = prep.camera.view.intrinsics.width;
  stats.image_height = prep.camera.view.intrinsics.height;
  stats.pyramid_level = prep.pyramid_level;
  stats.image_noise = prep.image_noise;
  stats.smoothing_px = prep.smoothing_px;
  stats.alpha = prep.alpha;
  stats.median_depth = prep.median_depth;
  stats.num_offsets = static_cast<int>(prep.offsets.size());
  stats.num_neighbours = static_cast<int>(prep.neighbours.size());
  stats.tiles_x = prep.tiles.tiles_x;
  stats.tiles_y = prep.tiles.tiles_y;
  stats.hypotheses =
      int64_t{stats.image_width} * stats.image_height * stats.num_offsets * stats.num_neighbours;
  return stats;
}

namespace {

// The largest value of a row, NaN ignored (-inf for none). Eight running maxima, so that the
// loop vectorises without reassociation.
MS_VECTOR_CLONES float RowMaximum(const float* __restrict values, int n) {
  float lanes[8];
  for (float& m : lanes) m = -std::numeric_limits<float>::infinity();
  int col = 0;
  for (; col + 8 <= n; col += 8) {
    for (int l = 0; l < 8; ++l) {
      const float v = values[col + l];
      lanes[l] = v > lanes[l] ? v : lanes[l];  // NaN compares false: ignored
    }
  }
  float m = -std::numeric_limits<float>::infinity();
  for (; col < n; ++col) m = values[col] > m ? values[col] : m;
  for (float l : lanes) m = l > m ? l : m;
  return m;
}

}  // namespace

bool BeatsInSweepOrder(const TileWinner& a, const TileWinner& b) {
  if (a.neighbour < 0) return false;
  if (b.neighbour < 0) return true;
  if (a.ncc != b.ncc) return a.ncc > b.ncc;
  return std::make_tuple(a.offset, a.neighbour, a.row, a.col) <
         std::make_tuple(b.offset, b.neighbour, b.row, b.col);
}

WinnerRule WinnerRule::For(const SweepOptions& options, int num_neighbours) {
  return WinnerRule{static_cast<float>(options.ncc_threshold),
                    std::clamp(options.min_matching_neighbours, 1, std::max(1, num_neighbours)),
                    static_cast<float>(options.support_ncc), options.strict_support,
                    options.winners_must_move};
}

std::vector<int> CompetingOffsets(const PreparedSweep& prep, const WinnerRule& rule) {
  std::vector<int> offsets;
  for (int k : prep.offsets) {
    if (k != 0 || !rule.must_move) offsets.push_back(k);
  }
  return offsets;
}

void UpdateTileWinners(const TileGrid& tiles, int offset, const std::vector<const float*>& ncc,
                       const std::vector<const float*>& surface, const int32_t* face,
                       const Eigen::Vector3d* world, const WinnerRule& rule,
                       std::vector<TileWinner>* best) {
  const int num_neighbours = static_cast<int>(ncc.size());
  MS_CHECK(rule.must_move ? offset != 0 && static_cast<int>(surface.size()) == num_neighbours
                          : surface.empty())
      << "tile winners of offset " << offset << " with " << surface.size() << " surface maps";
  // Enough support for neighbour j's match at a pixel (WinnerRule).
  const auto supported_at = [&](int j, size_t index) {
    int supporters = 1, defined = 1;
    for (int other = 0; other < num_neighbours; ++other) {
      if (other == j) continue;
      const float value = ncc[other][index];
      supporters += value > rule.support;
      defined += !std::isnan(value);
    }
    return supporters >=
           (rule.strict ? rule.required_matches : std::min(rule.required_matches, defined));
  };
  // Most rows of a tile hold no winner: their maxima tell (no pixel above both bars). They are
  // taken first, a whole row of the image at a time: tile by tile, each row's piece of a large
  // map lies on a page of its own and waits on memory.
  thread_local std::vector<float> row_maxima;  // [neighbour][row][tile column]
  const size_t per_map = static_cast<size_t>(tiles.height) * tiles.tiles_x;
  row_maxima.resize(per_map * num_neighbours);
  for (int j = 0; j < num_neighbours; ++j) {
    for (int row = 0; row < tiles.height; ++row) {
      const float* values = ncc[j] + static_cast<size_t>(row) * tiles.width;
      float* maxima = row_maxima.data() + j * per_map + static_cast<size_t>(row) * tiles.tiles_x;
      for (int tx = 0; tx < tiles.tiles_x; ++tx) {
        maxima[tx] = RowMaximum(values + tiles.XBegin(tx), tiles.XBegin(tx + 1) - tiles.XBegin(tx));
      }
    }
  }
  for (int ty = 0; ty < tiles.tiles_y; ++ty) {
    for (int tx = 0; tx < tiles.tiles_x; ++tx) {
      TileWinner& tile = (*best)[ty * tiles.tiles_x + tx];
      for (int j = 0; j < num_neighbours; ++j) {
        for (int row = tiles.YBegin(ty); row < tiles.YBegin(ty + 1); ++row) {
          const size_t row_offset = static_cast<size_t>(row) * tiles.width;
          const float* values = ncc[j] + row_offset;
          const float bar = std::max(rule.threshold, tile.ncc);
          if (row_maxima[j * per_map + static_cast<size_t>(row) * tiles.tiles_x + tx] <= bar) {
            continue;
          }
          for (int col = tiles.XBegin(tx); col < tiles.XBegin(tx + 1); ++col) {
            const float value = values[col];
            if (!(value > rule.threshold) || !(value > tile.ncc)) continue;  // NaN never wins
            const size_t index = row_offset + col;
            if (rule.required_matches > 1 && !supported_at(j, index)) continue;
            if (!surface.empty() && surface[j][index] >= value) continue;
            tile.ncc = value;
            tile.offset = offset;
            tile.neighbour = j;
            tile.col = col;
            tile.row = row;
            tile.face = face[index];
            if (world != nullptr) tile.position = world[index];
            tile.matched.clear();
            for (int other = 0; other < num_neighbours; ++other) {
              if (other != j && ncc[other][index] > rule.threshold) tile.matched.push_back(other);
            }
          }
        }
      }
    }
  }
}

SweepPoint MakeSweepPoint(const TileWinner& winner, const PreparedSweep& prep) {
  SweepPoint point;
  point.position = winner.position;
  point.ncc = winner.ncc;
  point.pixel = {static_cast<float>((winner.col + 0.5) / prep.scale_x),
                 static_cast<float>((winner.row + 0.5) / prep.scale_y)};
  point.offset = winner.offset;
  point.face = winner.face;
  point.cameras.reserve(2 + winner.matched.size());
  point.cameras.push_back(prep.camera.id);
  point.cameras.push_back(prep.neighbours[winner.neighbour].id);
  for (int other : winner.matched) point.cameras.push_back(prep.neighbours[other].id);
  return point;
}

int PyramidLevelToFit(int longest_side, int max_image_dimension) {
  int level = 0;
  if (max_image_dimension > 0) {
    while ((longest_side >> level) > max_image_dimension && level < 12) ++level;
  }
  return level;
}

int SweepPyramidLevel(int longest_side, const SweepOptions& options) {
  if (options.pyramid_level >= 0) return options.pyramid_level;
  return PyramidLevelToFit(longest_side, options.max_image_dimension);
}

SweepCamera CameraAtPyramidLevel(const SweepCamera& in, int level) {
  SweepCamera out = in;
  if (level == 0) return out;
  Intrinsics& k = out.view.intrinsics;
  const cv::Size size = SweptImageSize(k.width, k.height, level);
  const double sx = static_cast<double>(size.width) / k.width;
  const double sy = static_cast<double>(size.height) / k.height;
  k.fx *= sx;
  k.cx *= sx;
  k.fy *= sy;
  k.cy *= sy;
  k.width = size.width;
  k.height = size.height;
  if (!in.image.empty()) cv::resize(in.image, out.image, size, 0, 0, cv::INTER_AREA);
  return out;
}

cv::Size SweptImageSize(int width, int height, int level) {
  const double factor = std::ldexp(1.0, -level);
  return {std::max(1, static_cast<int>(std::lround(width * factor))),
          std::max(1, static_cast<int>(std::lround(height * factor)))};
}

void SmoothNoisyImages(const SweepOptions& options, PreparedSweep* prep) {
  std::vector<cv::Mat*> images = {&prep->camera.image};
  for (SweepCamera& n : prep->neighbours) images.push_back(&n.image);
  double noise = 0;  // in the images' units, gray in [0, 1]
  for (const cv::Mat* image : images) noise = std::max(noise, EstimateNoiseSigma(*image));
  prep->image_noise = 255 * noise;
  prep->smoothing_px =
      SmoothingSigmaPx(prep->image_noise, options.image_noise_target, options.gaussian_sigma_px);
  if (prep->smoothing_px == 0) return;
  for (cv::Mat* image : images) {
    if (image->empty()) continue;
    cv::Mat smoothed;  // never in place: level 0 shares the job's pixels
    cv::GaussianBlur(*image, smoothed, cv::Size(), prep->smoothing_px, prep->smoothing_px,
                     cv::BORDER_REFLECT_101);
    *image = smoothed;
  }
}

PreparedSweep PrepareSweep(const SweepJob& job) {
  CheckSweepJob(job);
  const SweepOptions& options = job.options;
  PreparedSweep prep;

  // Resolution: one level for the whole job so all cameras share the same pixel scale.
  int longest = std::max(job.camera.view.intrinsics.width, job.camera.view.intrinsics.height);
  for (const SweepCamera& n : job.neighbours) {
    longest = std::max({longest, n.view.intrinsics.width, n.view.intrinsics.height});
  }
  const int level = SweepPyramidLevel(longest, options);
  prep.pyramid_level = level;
  prep.camera = CameraAtPyramidLevel(job.camera, level);
  for (const SweepCamera& n : job.neighbours) {
    prep.neighbours.push_back(CameraAtPyramidLevel(n, level));
  }
  SmoothNoisyImages(options, &prep);
  prep.scale_x =
      static_cast<double>(prep.camera.view.intrinsics.width) / job.camera.view.intrinsics.width;
  prep.scale_y =
      static_cast<double>(prep.camera.view.intrinsics.height) / job.camera.view.intrinsics.height;

  // Median depth of the mesh vertices in front of C.
  std::vector<double> depths;
  for (const Eigen::Vector3d& v : job.mesh.vertices) {
    const double z = job.camera.view.ToCamera(v).z();
    if (z > 0) depths.push_back(z);
  }
  if (depths.empty()) {
    throw InputError(fmt::format("sweep job for camera {}: no mesh vertex in front of the camera",
                                 job.camera.id));
  }
  auto mid = depths.begin() + depths.size() / 2;
  std::nth_element(depths.begin(), mid, depths.end());
  prep.median_depth = *mid;
  prep.near = 1e-3 * prep.median_depth;

  prep.offsets = SweepOffsets(options.num_offsets);
  if (options.alpha > 0) {
    prep.alpha = options.alpha;
  } else {
    std::vector<View> views;
    for (const SweepCamera& n : prep.neighbours) views.push_back(n.view);
    prep.alpha = AutoSweepAlpha(prep.camera.view, views, job.mesh, options.alpha_parallax_px,
                                prep.median_depth);
  }
  prep.tiles = TileGrid::ForOptions(prep.camera.view.intrinsics.width,
                                    prep.camera.view.intrinsics.height, options);
  prep.window = GaussianWindow(options.gaussian_sigma_px);
  return prep;
}

}  // namespace ms
