#include "scene/scene.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "base/error.h"

namespace ms {

bool Observation::operator==(const Observation& o) const {
  const auto same = [](float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  return view == o.view && same(x, o.x) && same(y, o.y);
}

void Scene::Validate() const {
  const auto fail = [&](const std::string& what) {
    throw InputError((source.empty() ? std::string("scene") : source) + ": " + what);
  };
  for (size_t i = 0; i < views.size(); ++i) {
    const View& v = views[i];
    const std::string id = "view " + std::to_string(i) + " ('" + v.name + "')";
    const Intrinsics& k = v.intrinsics;
    if (!(k.width > 0 && k.height > 0)) fail(id + ": image size must be positive");
    if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && k.fx > 0 && k.fy > 0)) {
      fail(id + ": focal length must be finite and positive");
    }
    if (!(std::isfinite(k.cx) && std::isfinite(k.cy))) fail(id + ": principal point not finite");
    if (!(std::isfinite(k.k1) && std::isfinite(k.k2) && std::isfinite(k.p1) &&
          std::isfinite(k.p2) && std::isfinite(k.k3))) {
      fail(id + ": distortion not finite");
    }
    if (!v.t.allFinite()) fail(id + ": translation not finite");
    if (!IsRotation(v.R, 1e-4)) fail(id + ": rotation is not a proper rotation matrix");
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const ScenePoint& p = points[i];
    const std::string id = "point " + std::to_string(i);
    if (!p.position.allFinite()) fail(id + ": position not finite");
    int previous = -1;
    for (const Observation& o : p.observations) {
      if (o.view < 0 || o.view >= static_cast<int>(views.size())) {
        fail(id + ": observation refers to view " + std::to_string(o.view) + " of " +
             std::to_string(views.size()));
      }
      if (o.view <= previous) fail(id + ": observations not sorted by view or duplicated");
      previous = o.view;
    }
  }
}

void Scene::NormalizeObservations() {
  for (ScenePoint& p : points) {
    auto& obs = p.observations;
    std::stable_sort(obs.begin(), obs.end(),
                     [](const Observation& a, const Observation& b) { return a.view < b.view; });
    obs.erase(
        std::unique(obs.begin(), obs.end(),
                    [](const Observation& a, const Observation& b) { return a.view == b.view; }),
        obs.end());
  }
}

Scene SubsetOfViews(const Scene& scene, const std::vector<int>& keep, size_t min_views) {
  std::vector<int32_t> renumbered(scene.views.size(), -1);
  Scene out;
  out.source = scene.source;
  for (size_t k = 0; k < keep.size(); ++k) {
    const int v = keep[k];
    if (v < 0 || v >= static_cast<int>(scene.views.size()) || (k > 0 && v <= keep[k - 1])) {
      throw InputError(scene.source + ": view " + std::to_string(v) +
                       " is not a view of the scene, or not in ascending order (" +
                       std::to_string(scene.views.size()) + " views)");
    }
    renumbered[v] = static_cast<int32_t>(k);
    out.views.push_back(scene.views[v]);
  }
  for (const ScenePoint& p : scene.points) {
    ScenePoint point = p;
    point.observations.clear();
    for (const Observation& o : p.observations) {
      if (renumbered[o.view] < 0) continue;
      point.observations.push_back(o);
      point.observations.back().view = renumbered[o.view];
    }
    if (point.observations.size() >= min_views) out.points.push_back(std::move(point));
  }
  return out;
}

BoundingBox Scene::PointBounds() const {
  BoundingBox box;
  for (const ScenePoint& p : points) box.Extend(p.position);
  return box;
}

BoundingBox Scene::CameraBounds() const {
  BoundingBox box;
  for (const View& v : views) box.Extend(v.Center());
  return box;
}

size_t Scene::NumObservations() const {
  size_t n = 0;
  for (const ScenePoint& p : points) n += p.observations.size();
  return n;
}

double Scene::MedianViewingDistance() const {
  std::vector<double> distances;
  for (const ScenePoint& p : points) {
    for (const Observation& o : p.observations) {
      distances.push_back((views[o.view].Center() - p.position).norm());
    }
  }
  if (distances.empty()) {
    // No visibility: fall back to camera-to-point-centroid distances.
    const BoundingBox box = PointBounds();
    if (box.Empty()) return 0;
    for (const View& v : views) distances.push_back((v.Center() - box.Center()).norm());
  }
  if (distances.empty()) return 0;
  auto mid = distances.begin() + distances.size() / 2;
  std::nth_element(distances.begin(), mid, distances.end());
  return *mid;
}

std::string Scene::Summary() const {
  std::ostringstream out;
  out << views.size() << " views";
  if (!views.empty()) {
    out << " (" << views[0].intrinsics.width << "x" << views[0].intrinsics.height;
    const bool mixed = std::any_of(views.begin(), views.end(), [&](const View& v) {
      return v.intrinsics.width != views[0].intrinsics.width ||
             v.intrinsics.height != views[0].intrinsics.height;
    });
    out << (mixed ? " and others)" : ")");
  }
  const size_t obs = NumObservations();
  out << ", " << points.size() << " points, " << obs << " observations";
  if (!points.empty()) {
    out.precision(3);
    out << " (mean track " << static_cast<double>(obs) / points.size() << ")";
  }
  return out.str();
}

}  // namespace ms
