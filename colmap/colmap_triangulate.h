// The colmap route: a sparse point cloud with visibility for scenes that only have cameras with
// known poses (Strecha .camera files, Middlebury *_par.txt, or any scene with poses). Drives
// Debian's `colmap` (3.8): CPU SIFT feature extraction, exhaustive or sequential matching, then
// `point_triangulator` on a model holding the KNOWN poses and intrinsics, and imports the
// triangulated points. Poses and intrinsics never change; colmap only adds points.
// See docs/reference/colmap-route.md for the commands run, the options and measured timings.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene/colmap_io.h"
#include "scene/scene.h"

namespace ms {

struct ColmapTriangulateOptions {
  // The colmap executable: a path, or a name looked up in PATH (Debian package `colmap`).
  std::string colmap = "colmap";
  // Working directory for the database, image links, models and colmap.log. Empty: a fresh
  // temporary directory, removed at the end unless keep_workspace. A directory given here is
  // kept; files of an earlier run in it (database.db, images/, models, log) are replaced.
  std::string workspace;
  bool keep_workspace = false;
  // "exhaustive" (every pair; right for up to a few hundred views) or "sequential" (pairs of
  // views close in name order, for videos and rings).
  std::string matcher = "exhaustive";
  // SIFT runs on images whose longer side is scaled down to this (colmap's default, 3200, keeps
  // fountain-P11's 3072 x 2048 at full size). Keypoints come back in full-size pixels.
  int max_image_size = 3200;
  // Threads colmap uses in every stage; -1 = all cores.
  int threads = -1;
  void Check() const;  // throws InputError naming the field
};

// Wall-clock time of one stage (feature_extractor, exhaustive_matcher, point_triangulator, ...).
struct ColmapStageTime {
  std::string stage;
  double seconds = 0;
};

struct ColmapTriangulateResult {
  // The input views unchanged (names, image paths, poses, intrinsics) with colmap's points.
  Scene scene;
  std::string colmap_path;         // resolved executable
  std::string colmap_version;      // e.g. "COLMAP 3.8"
  int64_t num_keypoints = 0;       // SIFT features over all views
  int64_t num_verified_pairs = 0;  // image pairs with geometrically verified matches
  int64_t num_inlier_matches = 0;  // over those pairs
  std::vector<ColmapStageTime> stage_times;
  // Largest change colmap made to a known pose: rotation (Frobenius norm of R' - R) and
  // translation (|t' - t| / max(1, |t|)). Both stay ~1e-15: poses are fixed.
  double max_rotation_change = 0;
  double max_translation_change = 0;
};

// Runs the route on `cameras` (its points, if any, are ignored). Every view needs an existing
// image file (view.image_path). Throws InputError for bad input (fewer than two views, a missing
// or unreadable image, no colmap installed) and InternalError when colmap fails; both name the
// log whose tail is logged.
ColmapTriangulateResult TriangulateWithColmap(const Scene& cameras,
                                              const ColmapTriangulateOptions& options);

// ---- The steps, exposed for tests ---------------------------------------------------------

// Rows of colmap's database.db (tables images, cameras, keypoints, two_view_geometries).
struct ColmapDbImage {
  int64_t image_id = 0;
  std::string name;
  int64_t camera_id = 0;
  int64_t num_keypoints = 0;
};
struct ColmapDbCamera {
  int64_t camera_id = 0;
  int model = 0;  // COLMAP model id (1 = PINHOLE)
  int64_t width = 0, height = 0;
  std::vector<double> params;
  bool prior_focal_length = false;
};
struct ColmapDatabase {
  std::vector<ColmapDbImage> images;
  std::vector<ColmapDbCamera> cameras;
  int64_t num_verified_pairs = 0;
  int64_t num_inlier_matches = 0;
};

// Reads the tables above. Throws InputError naming the file if it is not a colmap database.
ColmapDatabase ReadColmapDatabase(const std::string& path);

// The COLMAP camera (model id and parameters) that holds `k` exactly: PINHOLE without
// distortion, OPENCV with k3 = 0, FULL_OPENCV otherwise.
ColmapDbCamera ColmapCameraFor(const Intrinsics& k);

// Sets the given cameras' model, size and parameters (prior_focal_length = 1) so matching
// verifies pairs with the known intrinsics. Cameras are matched by camera_id.
void WriteColmapDatabaseCameras(const std::string& path, const std::vector<ColmapDbCamera>& cams);

// Image names used inside the workspace (and so in the database): the view's own name when it
// is a plain relative path COLMAP can hold (no whitespace, no "..", not absolute) and unique;
// otherwise "ms_view_<index><extension of the image file>". Always unique.
std::vector<std::string> ColmapWorkspaceNames(const Scene& scene);

// Which database image and camera belong to each view.
struct ColmapIdMap {
  std::vector<int64_t> image_id;   // per view
  std::vector<int64_t> camera_id;  // per view
};

// Matches the database's images to the views by workspace name. Throws InputError naming the
// view and its image when colmap did not take a view's image in (it could not read it), and
// InternalError when the database holds images that are not ours or two views with different
// intrinsics share a camera.
ColmapIdMap MatchDatabaseToViews(const Scene& scene, const std::vector<std::string>& names,
                                 const ColmapDatabase& db, const std::string& db_name);

// The input model for point_triangulator: cameras and images with the database's ids, the
// known poses and intrinsics, empty POINTS2D lines (colmap fills in the database's keypoints)
// and no points. Text layout; numbers printed so they read back exactly.
ColmapFiles MakeKnownPoseModel(const Scene& scene, const std::vector<std::string>& names,
                               const ColmapIdMap& ids);

// Puts the triangulated points onto the input views: `triangulated` is colmap's model read back
// (views named by workspace name, in any order). Keeps the input's views exactly; remaps
// observations; fills the pose-change fields of `result`. Throws InternalError if a view is
// missing or colmap moved a pose beyond 1e-6 (relative).
Scene AttachTriangulatedPoints(const Scene& cameras, const std::vector<std::string>& names,
                               const Scene& triangulated, ColmapTriangulateResult* result);

// What feature_extractor's output says about an image it could not read: the text after
// "ERROR:" on the line after "Name: <name>" ("Failed to read image file format."); "" if none.
std::string ColmapImageError(const std::string& extraction_output, const std::string& name);

// First line of `colmap -h` output ("COLMAP 3.8 -- ...") reduced to "COLMAP 3.8"; "" if absent.
std::string ParseColmapVersion(const std::string& help_output);

}  // namespace ms
