// The scene: what an SfM run gives us and every later stage consumes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "scene/camera.h"

namespace ms {

// One sighting of a point in a view. Pixel coordinates may be NaN when the source format does
// not carry them (visibility only).
struct Observation {
  int32_t view = -1;
  float x = 0, y = 0;
  bool operator==(const Observation& o) const;
};

struct ScenePoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  std::array<uint8_t, 3> color{{128, 128, 128}};
  std::vector<Observation> observations;  // at most one per view, sorted by view
};

struct BoundingBox {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  void Extend(const Eigen::Vector3d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  bool Empty() const { return !(min.array() <= max.array()).all(); }
  Eigen::Vector3d Center() const { return 0.5 * (min + max); }
  double Diagonal() const { return Empty() ? 0.0 : (max - min).norm(); }
};

struct Scene {
  std::vector<View> views;
  std::vector<ScenePoint> points;
  std::string source;  // path/format it was read from, for messages

  // Checks structural validity: finite poses and points, rotations, positive focal lengths and
  // sizes, observation view indices in range, no duplicate view per point. Throws InputError
  // naming `source`, the view/point and the field.
  void Validate() const;

  // Sorts each point's observations by view and drops exact duplicates.
  void NormalizeObservations();

  BoundingBox PointBounds() const;
  BoundingBox CameraBounds() const;
  size_t NumObservations() const;
  // Median distance from camera centres to the points they see (a scene-scale measure).
  double MedianViewingDistance() const;
  // One line: "N views (WxH ...), M points, K observations (mean track L)".
  std::string Summary() const;
};

// The views `keep` (indices into scene.views, ascending, each once) renumbered 0, 1, ... and the
// points at least `min_views` of them observe, with only those observations: the model of a
// part of the images (`convert --keep-views`, a run to extend later). Throws InputError for an
// index out of range or out of order.
Scene SubsetOfViews(const Scene& scene, const std::vector<int>& keep, size_t min_views = 2);

}  // namespace ms
