// The mesh-sweeping kernel (paper section 2.2, docs/design/sweep.md): given a camera C, its
// neighbour cameras, their images and the part of the mesh C sees, sweep every facet along C's
// viewing rays, match C's image against each neighbour's image reprojected through every swept mesh
// (Gaussian-weighted NCC) and return the best point of every image tile.
//
// This header holds what every implementation shares: the job, its options and result, the
// interface, and the preparation (checks, resolution, alpha, tiles) so that the C++ reference
// and the GLSL kernel sweep exactly the same hypotheses.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "scene/camera.h"
#include "sweep/sweep_options.h"

namespace ms {

// A camera of a job: its scene index, calibration and image (gray CV_32FC1 in [0, 1], exactly
// intrinsics.width x intrinsics.height, undistorted: the kernel takes pinhole views only).
struct SweepCamera {
  int32_t id = -1;
  View view;
  cv::Mat image;
};

struct SweepJob {
  SweepCamera camera;                   // C
  std::vector<SweepCamera> neighbours;  // usually two (scene/view_selection.h)
  Mesh mesh;  // the part of the mesh C sees (mesh/visible_mesh.h); no need to be manifold
  SweepOptions options;
  uint32_t iteration = 0;  // of the run (1-based); only kernels that replay a recorded run use it
};

struct SweepPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // on the swept mesh that matched
  float ncc = 0;
  // Centre of the winning pixel in C's full-resolution image (corner-origin convention).
  Eigen::Vector2f pixel = Eigen::Vector2f::Zero();
  int32_t offset = 0;  // k of the swept mesh
  int32_t face = -1;   // face of the job's mesh that produced it
  // C's id first, then the neighbour that won, then any other neighbour whose NCC at the same
  // pixel and offset is also above the threshold.
  std::vector<int32_t> cameras;
};

struct SweepStats {
  int image_width = 0, image_height = 0;  // swept resolution
  int pyramid_level = 0;
  double image_noise = 0;   // grey levels (of 255), the job's noisiest image at that level
  double smoothing_px = 0;  // sigma of the Gaussian its images were smoothed with (0: none)
  double alpha = 0;         // scene units, as used
  double median_depth = 0;  // of the visible mesh's vertices in C
  int num_offsets = 0;      // swept meshes (2*floor((N-1)/2)+1)
  int num_neighbours = 0;
  int tiles_x = 0, tiles_y = 0;
  int64_t covered_pixels = 0;    // C pixels covered by a swept mesh, summed over offsets
  int64_t hypotheses = 0;        // image pixels x offsets x neighbours (the benchmark's unit)
  int64_t valid_hypotheses = 0;  // of which got an NCC (covered, visible, textured)
  double prepare_s = 0, raster_s = 0, reproject_s = 0, ncc_s = 0, reduce_s = 0, total_s = 0;
  std::string Summary() const;  // one line for the log
};

struct SweepResult {
  std::vector<SweepPoint> points;  // at most one per tile, in tile order (row-major)
  SweepStats stats;
};

class SweepKernel {
 public:
  virtual ~SweepKernel() = default;
  // Throws InputError for a bad job (see CheckSweepJob), never crashes on one.
  virtual SweepResult Run(const SweepJob& job) = 0;
  virtual std::string Name() const = 0;
  // False for a kernel that never reads the job's images (a replay of recorded results): the
  // worker then neither fetches nor decodes them.
  virtual bool NeedsImages() const { return true; }
};

// ---- Shared preparation: every kernel must sweep exactly these hypotheses. ----

// Throws InputError naming the camera and the problem: bad options, an empty or malformed mesh,
// no neighbour, a neighbour at C's centre, an invalid or distorted view, a missing image, an
// image not CV_32FC1 or of a size other than its view's, non-finite pixels, or a mesh with no
// face in front of C inside its image.
void CheckSweepJob(const SweepJob& job);

// The offsets k, ascending: -K..K with K = floor((N-1)/2), i.e. every integer in (-N/2, N/2).
std::vector<int> SweepOffsets(int num_offsets);

// The swept position of vertex v of a facet with unit normal n, for camera centre c:
// v + alpha_k |cos(theta)| d, d = (v - c)/|v - c|, cos(theta) = n.d. Positive alpha_k moves the
// vertex away from the camera whatever the facet's orientation; a degenerate facet (n = 0)
// does not move.
Eigen::Vector3d SweepVertex(const Eigen::Vector3d& v, const Eigen::Vector3d& n,
                            const Eigen::Vector3d& c, double alpha_k);

// Tile t covers columns [x_begin(t), x_begin(t+1)) with x_begin(t) = floor(t*W/tiles_x), and
// likewise rows.
struct TileGrid {
  int width = 0, height = 0, tiles_x = 1, tiles_y = 1;
  // round(W / tile_size) x round(H / tile_size) tiles, at least 1 x 1, at most one per pixel.
  static TileGrid Make(int width, int height, double tile_size_px);
  // The longer side / options.tiles_across, or (0) options.tile_size_px.
  static TileGrid ForOptions(int width, int height, const SweepOptions& options);
  int XBegin(int tx) const { return static_cast<int>(int64_t{tx} * width / tiles_x); }
  int YBegin(int ty) const { return static_cast<int>(int64_t{ty} * height / tiles_y); }
  int NumTiles() const { return tiles_x * tiles_y; }
};

// The Gaussian window weights w_i = exp(-i^2 / (2 sigma^2)), i = -r..r with r = ceil(3 sigma),
// normalised to sum 1 (CV_32F column vector).
cv::Mat GaussianWindow(double sigma_px);

// A job ready to sweep: views and images at the swept resolution, alpha, offsets, tiles.
struct PreparedSweep {
  int pyramid_level = 0;
  double scale_x = 1, scale_y = 1;  // swept / full-resolution pixel coordinates
  SweepCamera camera;               // at the swept resolution (id and pose as in the job)
  std::vector<SweepCamera> neighbours;
  double image_noise = 0;   // grey levels (of 255), the noisiest image at the swept resolution
  double smoothing_px = 0;  // sigma every image was smoothed with (0: none; SmoothNoisyImages)
  std::vector<int> offsets;
  double alpha = 0;
  double median_depth = 0;
  // Near clipping plane for every rendering (camera z, scene units): 1e-3 x median depth.
  double near = 0;
  TileGrid tiles;
  cv::Mat window;  // GaussianWindow(options.gaussian_sigma_px)
};

// The pyramid level of a job whose largest image side is `longest_side`: options.pyramid_level
// if set, else the smallest level at which that side fits max_image_dimension (0: full size).
int SweepPyramidLevel(int longest_side, const SweepOptions& options);
// The smallest level at which `longest_side` fits max_image_dimension (0: any size, level 0).
int PyramidLevelToFit(int longest_side, int max_image_dimension);
// An image's size at a pyramid level, as PrepareSweep resizes it (rounded, at least 1 x 1).
cv::Size SweptImageSize(int width, int height, int level);
// The camera at a pyramid level: its image resized (cv::INTER_AREA) to SweptImageSize and its
// intrinsics scaled by the size ratios (fx, cx by the width's, fy, cy by the height's: exact with
// the corner-origin convention). Level 0 returns it as it is. A camera without an image (its
// geometry only) stays without one.
SweepCamera CameraAtPyramidLevel(const SweepCamera& camera, int level);

// Estimates the noise of the prepared images (the noisiest one's) and, if it is above
// options.image_noise_target, smooths them all with the same Gaussian (sweep/image_noise.h): one
// filter for all, so that a perfect match stays one.
void SmoothNoisyImages(const SweepOptions& options, PreparedSweep* prep);

// Checks the job (CheckSweepJob), picks the pyramid level, resizes images (cv::INTER_AREA) and
// scales intrinsics (fx, cx by the width ratio, fy, cy by the height ratio: exact with the
// corner-origin convention), smooths noisy images (SmoothNoisyImages), and derives alpha
// (docs/design/sweep.md).
PreparedSweep PrepareSweep(const SweepJob& job);

// The stats every kernel knows before sweeping: the swept resolution, level, alpha, median
// depth, offsets, neighbours, tiles and hypotheses (times and counts left at zero).
SweepStats PreparedSweepStats(const PreparedSweep& prep);

// The best hypothesis of one tile, as a kernel's tile-best step keeps it. "No winner" is
// neighbour < 0 (the defaults).
struct TileWinner {
  float ncc = -std::numeric_limits<float>::infinity();
  int offset = 0;          // k
  int neighbour = -1;      // index into the job's neighbours of the one that won
  int col = -1, row = -1;  // pixel at the swept resolution
  int32_t face = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world
  // The other neighbours (indices, ascending) whose NCC at the same pixel and offset is above
  // the threshold.
  std::vector<int> matched;
};

// What a pixel's NCC needs to win its tile, the same in every kernel (the GLSL kernel passes it
// as uniforms): strictly above `threshold` (t_NCC), and support from `required_matches`
// neighbours at that pixel and offset (its own, and the others whose NCC there is above
// `support`). Unless `strict`, fewer suffice where fewer neighbours see the pixel; strict, a
// neighbour that does not see it cannot support it.
// The values come from the options (For): no defaults of its own, so none can drift from them.
struct WinnerRule {
  float threshold;
  int required_matches;
  float support;
  bool strict;
  // The unswept mesh (k = 0) competes for nothing, and a pixel competes at k != 0 only where its
  // NCC beats neighbour j's at k = 0 (the `surface` maps). Else k = 0 competes like any offset.
  bool must_move;

  // From the options; required_matches is min_matching_neighbours clamped to [1, the job's
  // neighbours].
  static WinnerRule For(const SweepOptions& options, int num_neighbours);
};

// The offsets that compete for tiles under `rule`, ascending: all of prep.offsets, or, where
// winners must move, all but k = 0, whose NCC maps are then swept first as the `surface` of
// UpdateTileWinners.
std::vector<int> CompetingOffsets(const PreparedSweep& prep, const WinnerRule& rule);

// One offset's contribution to the tile winners, as every kernel keeps them: a pixel whose NCC
// (ncc[j], row-major at the swept resolution, NaN where undefined) meets `rule` and is strictly
// above its tile's best wins; ties go to the smaller k (offsets in ascending order), then the
// earlier neighbour, then the earlier pixel in row-major order. `face` gives each pixel's face;
// `world`, when not null, its position (else left as is). Where rule.must_move, `surface` holds
// each neighbour's NCC at k = 0 (same layout; empty otherwise), which neighbour j's NCC must beat
// at the pixel (where it is undefined, nothing to beat).
void UpdateTileWinners(const TileGrid& tiles, int offset, const std::vector<const float*>& ncc,
                       const std::vector<const float*>& surface, const int32_t* face,
                       const Eigen::Vector3d* world, const WinnerRule& rule,
                       std::vector<TileWinner>* best);

// Whether tile winner a beats b as UpdateTileWinners would decide had it seen both: the higher
// NCC, on ties the smaller k, then the earlier neighbour, then the earlier pixel. An empty
// winner (neighbour < 0) beats nothing. For merging winners found by threads over disjoint
// offsets.
bool BeatsInSweepOrder(const TileWinner& a, const TileWinner& b);

// The point of a tile winner: its pixel centre in C's full-resolution image, C's id, then the
// winning neighbour's, then those of the other neighbours that matched (both kernels).
SweepPoint MakeSweepPoint(const TileWinner& winner, const PreparedSweep& prep);

// The automatic alpha: alpha_parallax_px / median over visible vertices X and neighbours j of
// |d pi_j(X + s d) / ds| at s = 0 (pixels per scene unit moved along C's ray), clamped to at
// most 0.02 x median depth. Views must be at the swept resolution.
double AutoSweepAlpha(const View& camera, const std::vector<View>& neighbours, const Mesh& mesh,
                      double parallax_px, double median_depth);

}  // namespace ms
