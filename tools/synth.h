// Synthetic datasets with exact ground truth (`manisweep synth`): rendered images, cameras, a
// sparse point cloud with visibility, and the ground-truth mesh. Built in memory by
// MakeSynthDataset (what tests use), written by WriteSynthDataset. Deterministic for a seed.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "gl/context.h"
#include "mesh/mesh.h"
#include "scene/scene.h"
#include "tools/synth_scenes.h"

namespace ms {

struct SynthOptions {
  std::string scene = "pyramid-down";  // pyramid-down, pyramid-up, blob, city
  int views = 0;                       // 0: the scene's default (pyramids 16, blob 24, city 60)
  int width = 0;                       // 0: the scene's default (800, city 1024)
  int height = 0;                      // 0: the scene's default (600, city 768)
  uint64_t seed = 1;                   // texture, shape (blob), layout (city), sampling and noise
  double image_noise = 0;  // standard deviation of Gaussian pixel noise, in grey levels (0-255)
  double point_noise = 0;  // standard deviation of Gaussian noise on sparse points, scene units
  int points = 0;          // blob/city: sparse points wanted (0: 3000 for blob, 40 per view for
                           // city); pyramids always get the 4 base corners
  int min_track = 2;       // blob/city: keep points seen by at least this many views
  double max_grazing_deg = 75;  // a point is seen only if its surface faces the camera closer
                                // than this to head-on
  bool render_images = true;    // false: cameras, points and mesh only (no GL needed)
  int supersampling = 2;        // anti-aliasing: render k x k samples per pixel
  std::vector<std::string> texture_photos;  // photographs (files) mixed into the texture
  void Check() const;                       // throws InputError naming the field
};

struct SynthDataset {
  std::string scene_name;
  SynthOptions options;  // as used, defaults resolved
  // Views are named "0000.png", ... (image_path empty until written); points carry their
  // observations (pixel = projection of the exact point, before point noise).
  Scene scene;
  Mesh ground_truth;
  Mesh initial_mesh;            // pyramids: the base square (the paper's initial manifold)
  std::vector<cv::Mat> images;  // CV_8UC3 BGR, one per view; empty without render_images
  int evaluation_view = 0;      // the view `manisweep evaluate` uses by default
  std::vector<Eigen::Vector3d> exact_points;  // sparse points before point noise
  std::vector<int32_t> point_faces;           // ground-truth face of each point (-1: a corner)
  double seconds_geometry = 0, seconds_points = 0, seconds_images = 0;
};

// Builds the dataset. `context` may be null when options.render_images is false.
SynthDataset MakeSynthDataset(const SynthOptions& options, const gl::GlContext* context);

// Writes into `directory` (created): images/NNNN.png, sparse/ (COLMAP text), scene.h5, gt.ply,
// initial.ply (pyramids) and synth.json (options, counts, evaluation view). Each file is written
// atomically.
void WriteSynthDataset(const SynthDataset& dataset, const std::string& directory);

// Expands files and directories (their *.jpg, *.jpeg, *.png, sorted) into a list of image files.
std::vector<std::string> ListPhotos(const std::vector<std::string>& paths);

}  // namespace ms
