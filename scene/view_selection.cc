#include "scene/view_selection.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "base/error.h"

namespace ms {

std::vector<int> SelectNeighbours(const Scene& scene, int camera, const NeighbourOptions& options) {
  options.Check();
  const int num_views = static_cast<int>(scene.views.size());
  if (camera < 0 || camera >= num_views) {
    throw InputError((scene.source.empty() ? std::string("scene") : scene.source) + ": camera " +
                     std::to_string(camera) + " is not a view of the scene (it has " +
                     std::to_string(num_views) + " views)");
  }
  const View& view = scene.views[camera];
  const Eigen::Vector3d center = view.Center();
  const Eigen::Vector3d axis = view.Axis().normalized();
  const double min_distance = options.same_center_fraction * scene.CameraBounds().Diagonal();
  const double cos_bound = std::cos(options.max_angle_deg * M_PI / 180.0);

  std::vector<std::pair<double, int>> candidates;  // (distance, index)
  for (int i = 0; i < num_views; ++i) {
    if (i == camera) continue;
    const View& other = scene.views[i];
    const double distance = (other.Center() - center).norm();
    if (!std::isfinite(distance) || distance <= min_distance) continue;
    // Angle strictly below the bound <=> cosine strictly above cos(bound).
    const double cos_angle = std::clamp(axis.dot(other.Axis().normalized()), -1.0, 1.0);
    if (options.max_angle_deg < 180 && !(cos_angle > cos_bound)) continue;
    candidates.emplace_back(distance, i);
  }
  std::sort(candidates.begin(), candidates.end());  // distance, then index
  std::vector<int> result;
  for (const auto& c : candidates) {
    if (static_cast<int>(result.size()) >= options.count) break;
    result.push_back(c.second);
  }
  return result;
}

std::vector<int> SelectNeighbours(const Scene& scene, int camera, double max_angle_deg, int count) {
  NeighbourOptions options;
  options.max_angle_deg = max_angle_deg;
  options.count = count;
  return SelectNeighbours(scene, camera, options);
}

}  // namespace ms
