#include "bench/bench_scenes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <string>
#include <tuple>

namespace ms::bench {

namespace {
double BlobRadius(const Eigen::Vector3d& n) {
  return 1.0 + 0.08 * std::sin(5 * n.x()) * std::cos(4 * n.y()) + 0.07 * std::sin(7 * n.z() + 1);
}
}  // namespace

ManifoldBenchScene MakeBlobScene(int64_t num_points, int num_cameras, int rays_per_point,
                                 uint64_t seed, double surface_offset) {
  ManifoldBenchScene scene;
  for (int c = 0; c < num_cameras; ++c) {
    const double angle = 2 * M_PI * c / num_cameras;
    const double height = (c % 2 == 0) ? 1.2 : -1.2;
    ManifoldCamera cam;
    cam.center = Eigen::Vector3d(3.5 * std::cos(angle), 3.5 * std::sin(angle), height);
    const Eigen::Vector3d z = (-cam.center).normalized();
    const Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(z).normalized();
    cam.R.row(0) = x;
    cam.R.row(1) = z.cross(x);
    cam.R.row(2) = z;
    cam.u_min = cam.v_min = -0.5;
    cam.u_max = cam.v_max = 0.5;
    scene.cameras.push_back(cam);
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  scene.points.resize(num_points);
  std::vector<std::pair<double, int>> facing(num_cameras);
  for (int64_t i = 0; i < num_points; ++i) {
    Eigen::Vector3d n(g(rng), g(rng), g(rng));
    n.normalize();
    RayPoint& p = scene.points[i];
    p.position = (BlobRadius(n) + surface_offset) * n;
    for (int c = 0; c < num_cameras; ++c) {
      facing[c] = {-n.dot((scene.cameras[c].center - p.position).normalized()), c};
    }
    std::partial_sort(facing.begin(), facing.begin() + rays_per_point, facing.end());
    for (int k = 0; k < rays_per_point; ++k) {
      if (facing[k].first < -0.05) p.cameras.push_back(facing[k].second);
    }
    std::sort(p.cameras.begin(), p.cameras.end());
  }
  return scene;
}

void SortLikeTheCoordinator(const std::vector<ManifoldCamera>& cameras,
                            std::vector<RayPoint>* points) {
  struct Keyed {
    int32_t camera, row, column;
    size_t index;
    bool operator<(const Keyed& o) const {
      return std::tie(camera, row, column, index) < std::tie(o.camera, o.row, o.column, o.index);
    }
  };
  std::vector<Keyed> keyed;
  keyed.reserve(points->size());
  for (size_t i = 0; i < points->size(); ++i) {
    const RayPoint& p = (*points)[i];
    Keyed k{-1, 0, 0, i};
    if (!p.cameras.empty()) {
      const ManifoldCamera& cam = cameras[p.cameras.front()];
      const Eigen::Vector3d x = cam.R * (p.position - cam.center);
      k.camera = p.cameras.front();
      k.column = static_cast<int32_t>(800 * (x.x() / x.z() - cam.u_min) / (cam.u_max - cam.u_min));
      k.row = static_cast<int32_t>(600 * (x.y() / x.z() - cam.v_min) / (cam.v_max - cam.v_min));
    }
    keyed.push_back(k);
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<RayPoint> sorted;
  sorted.reserve(points->size());
  for (const Keyed& k : keyed) sorted.push_back(std::move((*points)[k.index]));
  *points = std::move(sorted);
}

}  // namespace ms::bench
