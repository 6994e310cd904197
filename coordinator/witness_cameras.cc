#include "coordinator/witness_cameras.h"

#include <algorithm>
#include <atomic>
#include <cstddef>

#include "base/parallel_for.h"
#include "scene/view_selection.h"

namespace ms {

std::vector<std::vector<int>> WitnessCandidates(const Scene& scene) {
  std::vector<std::vector<int>> candidates(scene.views.size());
  ParallelFor(scene.views.size(), [&](size_t c) {
    candidates[c] = SelectNeighbours(scene, static_cast<int>(c), 180, kWitnessCandidates);
    std::sort(candidates[c].begin(), candidates[c].end());
  });
  return candidates;
}

WitnessCameras::WitnessCameras(const Scene& scene, const std::vector<std::vector<int>>& candidates,
                               const Mesh& mesh, double relative_tolerance)
    : scene_(scene),
      candidates_(candidates),
      caster_(mesh),
      relative_tolerance_(relative_tolerance) {}

bool WitnessCameras::Sees(int camera, const Eigen::Vector3d& point) const {
  const View& view = scene_.views[camera];
  Eigen::Vector2d pixel;
  if (!view.Project(point, &pixel)) return false;
  const Intrinsics& k = view.intrinsics;
  if (!(pixel.x() >= 0 && pixel.y() >= 0 && pixel.x() < k.width && pixel.y() < k.height)) {
    return false;
  }
  const Eigen::Vector3d center = view.Center();
  return !caster_.Occluded(center, point, relative_tolerance_ * (point - center).norm());
}

int64_t WitnessCameras::Add(std::vector<RayPoint>* points) const {
  std::atomic<int64_t> added{0};
  ParallelFor(points->size(), [&](size_t i) {
    RayPoint& p = (*points)[i];
    if (p.cameras.empty()) return;
    const auto matched = static_cast<std::ptrdiff_t>(p.cameras.size());  // C and its matches
    for (int c : candidates_[p.cameras.front()]) {
      const auto matched_end = p.cameras.begin() + matched;  // anew: push_back reallocates
      if (std::find(p.cameras.begin(), matched_end, c) != matched_end) continue;
      if (!Sees(c, p.position)) continue;
      p.cameras.push_back(c);
      added.fetch_add(1, std::memory_order_relaxed);
    }
  });
  return added.load();
}

}  // namespace ms
