#include "bench/bench_scenes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <string>

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

int64_t PeakRssBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6)) * 1024;
  }
  return 0;
}

}  // namespace ms::bench
