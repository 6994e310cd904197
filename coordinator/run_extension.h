// Adding images to a finished run (`manisweep extend`, docs/design/extend.md): the new SfM
// model, holding the run's cameras and new ones in the same frame, becomes the run's scene with
// the new views and the new points appended; the new points, with their rays from old and new
// cameras, are the extension's batch.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "base/options.h"
#include "manifold/delaunay_manifold.h"
#include "scene/scene.h"

namespace ms {

struct ExtendOptions {
  static constexpr const char* kOptionGroup = "extend";
#define MS_OPTION_LIST "coordinator/extend_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

// One extension as run.h5 records it: after the first `points_before` scene points built the
// manifold (or an earlier extension added them), iteration `iteration` added the views
// [views_before, views_after) and took the points [points_before, points_after) as its batch.
// Replaying it builds the manifold anew with those cameras and points, as the extension did.
struct RunExtension {
  int32_t iteration = 0;
  int32_t views_before = 0, views_after = 0;
  int64_t points_before = 0, points_after = 0;
};

struct ExtendedScene {
  Scene scene;             // the run's views and points, then the new ones
  RunExtension extension;  // without its iteration (the caller's)
  double worst_shift = 0;  // of an old camera's centre, in scene units
  double worst_turn_deg = 0;
  int64_t model_points = 0;  // points of the new model
};

// The run's scene extended by `model` (read from `model_path`): views matched by name (every
// view of the run must be in the model), the model's other views appended in its order, and the
// model's points seen by at least one new view appended with their observations renumbered.
// Throws InputError naming the model, the camera and the distance when an old camera moved
// past the options' bounds, when a view of the run is missing, or when the model adds no view.
ExtendedScene ExtendScene(const Scene& run_scene, const Scene& model, const std::string& model_path,
                          const ExtendOptions& options);

// The cameras an extension sweeps (1 each): the new ones, their neighbours, and the old ones that
// look into the new cameras' region: those that see at least `min_shared` as many of the
// extension's points as of the points they were reconstructed from (a camera at the end of a
// street looking down it sees the part the new images add; its neighbours by position are old).
std::vector<uint8_t> ExtensionSweptCameras(const Scene& scene, const RunExtension& extension,
                                           const std::vector<std::vector<int>>& neighbours,
                                           double min_shared = 0.5);

// The extension's batch: one RayPoint per appended point, with all its views.
std::vector<RayPoint> ExtensionBatch(const Scene& scene, const RunExtension& extension);

}  // namespace ms
