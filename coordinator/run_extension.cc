#include "coordinator/run_extension.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "base/error.h"

namespace ms {
namespace {

constexpr double kDegrees = 180.0 / 3.14159265358979323846;

// The angle of the rotation that takes a to b, in degrees.
double TurnDegrees(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double cosine = std::clamp(((a.transpose() * b).trace() - 1) / 2, -1.0, 1.0);
  return std::acos(cosine) * kDegrees;
}

}  // namespace

ExtendedScene ExtendScene(const Scene& run_scene, const Scene& model, const std::string& model_path,
                          const ExtendOptions& options) {
  std::map<std::string, int32_t> model_view;
  for (size_t v = 0; v < model.views.size(); ++v) {
    if (!model_view.emplace(model.views[v].name, static_cast<int32_t>(v)).second) {
      throw InputError(fmt::format("{}: image {} appears twice", model_path, model.views[v].name));
    }
  }
  ExtendedScene out;
  out.scene = run_scene;
  out.model_points = static_cast<int64_t>(model.points.size());
  const int32_t old_views = static_cast<int32_t>(run_scene.views.size());
  // Model view -> view of the extended scene.
  std::vector<int32_t> merged(model.views.size(), -1);
  const double scale = run_scene.MedianViewingDistance();
  const double max_shift = options.max_camera_shift * scale;
  for (int32_t v = 0; v < old_views; ++v) {
    const View& old_view = run_scene.views[v];
    const auto found = model_view.find(old_view.name);
    if (found == model_view.end()) {
      throw InputError(fmt::format(
          "{}: image {} of the run (camera {}) is not in the model: the model must hold every "
          "camera of the run and the new ones, in the run's frame",
          model_path, old_view.name, v));
    }
    const View& now = model.views[found->second];
    const double shift = (now.Center() - old_view.Center()).norm();
    const double turn = TurnDegrees(old_view.R, now.R);
    if (shift > max_shift || turn > options.max_camera_turn_deg) {
      throw InputError(fmt::format(
          "{}: camera {} ({}) moved by {:.4g} ({:.3g} of the run's median viewing distance "
          "{:.4g}; --extend.max-camera-shift {}) and turned by {:.3g} degrees "
          "(--extend.max-camera-turn-deg {}): the model is not in the run's frame, or its old "
          "cameras moved; register the new images into the run's model without moving them",
          model_path, v, old_view.name, shift, scale > 0 ? shift / scale : 0.0, scale,
          options.max_camera_shift, turn, options.max_camera_turn_deg));
    }
    out.worst_shift = std::max(out.worst_shift, shift);
    out.worst_turn_deg = std::max(out.worst_turn_deg, turn);
    merged[found->second] = v;
  }
  for (size_t v = 0; v < model.views.size(); ++v) {
    if (merged[v] >= 0) continue;
    merged[v] = static_cast<int32_t>(out.scene.views.size());
    out.scene.views.push_back(model.views[v]);
  }
  const int32_t all_views = static_cast<int32_t>(out.scene.views.size());
  if (all_views == old_views) {
    throw InputError(
        fmt::format("{}: no new image: every one of its {} images is a camera of the run already",
                    model_path, model.views.size()));
  }
  const int64_t old_points = static_cast<int64_t>(run_scene.points.size());
  for (const ScenePoint& p : model.points) {
    ScenePoint point = p;
    bool seen_by_new = false;
    for (Observation& o : point.observations) {
      o.view = merged[o.view];
      seen_by_new |= o.view >= old_views;
    }
    if (!seen_by_new) continue;  // the run has it, or a point like it, already
    std::sort(point.observations.begin(), point.observations.end(),
              [](const Observation& a, const Observation& b) { return a.view < b.view; });
    out.scene.points.push_back(std::move(point));
  }
  out.scene.source = model_path;
  out.extension.views_before = old_views;
  out.extension.views_after = all_views;
  out.extension.points_before = old_points;
  out.extension.points_after = static_cast<int64_t>(out.scene.points.size());
  return out;
}

std::vector<uint8_t> ExtensionSweptCameras(const Scene& scene, const RunExtension& extension,
                                           const std::vector<std::vector<int>>& neighbours,
                                           double min_shared) {
  std::vector<uint8_t> swept(scene.views.size(), 0);
  std::vector<int64_t> before(scene.views.size(), 0), shared(scene.views.size(), 0);
  for (int64_t i = 0; i < extension.points_after; ++i) {
    std::vector<int64_t>& count = i < extension.points_before ? before : shared;
    for (const Observation& o : scene.points[i].observations) ++count[o.view];
  }
  for (int32_t c = 0; c < extension.views_before; ++c) {
    swept[c] = shared[c] > 0 && shared[c] >= min_shared * before[c];
  }
  for (int32_t c = extension.views_before; c < extension.views_after; ++c) {
    swept[c] = 1;
    for (int n : neighbours[c]) swept[n] = 1;
  }
  return swept;
}

std::vector<RayPoint> ExtensionBatch(const Scene& scene, const RunExtension& extension) {
  std::vector<RayPoint> batch;
  for (int64_t i = extension.points_before; i < extension.points_after; ++i) {
    const ScenePoint& p = scene.points[i];
    RayPoint point;
    point.position = p.position;
    for (const Observation& o : p.observations) point.cameras.push_back(o.view);
    batch.push_back(std::move(point));
  }
  return batch;
}

}  // namespace ms
