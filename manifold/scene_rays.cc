#include "manifold/scene_rays.h"

#include <cmath>

namespace ms {

std::vector<ManifoldCamera> ManifoldCamerasFromScene(const Scene& scene) {
  std::vector<ManifoldCamera> cameras;
  cameras.reserve(scene.views.size());
  for (const View& view : scene.views) {
    const Intrinsics& k = view.intrinsics;
    ManifoldCamera camera;
    camera.center = view.Center();
    camera.R = view.R;
    camera.u_min = (0 - k.cx) / k.fx;
    camera.u_max = (k.width - k.cx) / k.fx;
    camera.v_min = (0 - k.cy) / k.fy;
    camera.v_max = (k.height - k.cy) / k.fy;
    camera.pixel_angle = 1.0 / std::sqrt(k.fx * k.fy);
    cameras.push_back(camera);
  }
  return cameras;
}

std::vector<RayPoint> RayPointsFromScene(const Scene& scene) {
  std::vector<RayPoint> points;
  points.reserve(scene.points.size());
  for (const ScenePoint& p : scene.points) {
    RayPoint ray_point;
    ray_point.position = p.position;
    ray_point.cameras.reserve(p.observations.size());
    for (const Observation& o : p.observations) ray_point.cameras.push_back(o.view);
    points.push_back(std::move(ray_point));
  }
  return points;
}

}  // namespace ms
