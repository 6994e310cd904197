#include "coordinator/ray_index.h"

#include <algorithm>
#include <cmath>

#include "base/check.h"

namespace ms {

RayIndex::RayIndex(std::vector<Camera> cameras, int grid) : grid_(std::max(grid, 1)) {
  cameras_.resize(cameras.size());
  for (size_t c = 0; c < cameras.size(); ++c) {
    CameraBuckets& cb = cameras_[c];
    cb.camera = cameras[c];
    MS_CHECK(cb.camera.u_max > cb.camera.u_min && cb.camera.v_max > cb.camera.v_min);
    cb.du = (cb.camera.u_max - cb.camera.u_min) / grid_;
    cb.dv = (cb.camera.v_max - cb.camera.v_min) / grid_;
    cb.buckets.resize(static_cast<size_t>(grid_) * grid_);
  }
}

void RayIndex::Add(int32_t camera, int32_t point, const Eigen::Vector3d& position) {
  MS_CHECK(camera >= 0 && camera < num_cameras()) << camera;
  CameraBuckets& cb = cameras_[camera];
  const Eigen::Vector3d x = cb.camera.R * (position - cb.camera.center);
  ++cb.count;
  ++size_;
  if (!(x.z() > 0)) {
    cb.overflow.push_back({point, static_cast<float>(x.z())});
    return;
  }
  const double u = x.x() / x.z(), v = x.y() / x.z();
  const double fu = std::floor((u - cb.camera.u_min) / cb.du);
  const double fv = std::floor((v - cb.camera.v_min) / cb.dv);
  if (!(fu >= 0 && fu < grid_ && fv >= 0 && fv < grid_)) {
    cb.overflow.push_back({point, static_cast<float>(x.z())});
    return;
  }
  cb.buckets[static_cast<size_t>(fv) * grid_ + static_cast<size_t>(fu)].push_back(
      {point, static_cast<float>(x.z())});
}

void RayIndex::Query(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                     std::vector<RayRef>* out) const {
  for (size_t c = 0; c < cameras_.size(); ++c) {
    const CameraBuckets& cb = cameras_[c];
    if (cb.count == 0) continue;
    const int32_t camera = static_cast<int32_t>(c);
    // Box corners in the camera frame.
    double z_min = INFINITY, z_max = -INFINITY;
    double u_lo = INFINITY, u_hi = -INFINITY, v_lo = INFINITY, v_hi = -INFINITY;
    bool straddles = false;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d w((corner & 1) ? max.x() : min.x(), (corner & 2) ? max.y() : min.y(),
                              (corner & 4) ? max.z() : min.z());
      const Eigen::Vector3d x = cb.camera.R * (w - cb.camera.center);
      z_min = std::min(z_min, x.z());
      z_max = std::max(z_max, x.z());
      if (x.z() <= 0) {
        straddles = true;
        continue;
      }
      u_lo = std::min(u_lo, x.x() / x.z());
      u_hi = std::max(u_hi, x.x() / x.z());
      v_lo = std::min(v_lo, x.y() / x.z());
      v_hi = std::max(v_hi, x.y() / x.z());
    }
    // Segments run from the camera (z = 0) to their end point (z > 0 for visible points): a
    // box entirely behind the camera meets none of them.
    if (z_max < 0) {
      for (const Entry& e : cb.overflow) {
        if (e.depth <= 0) out->push_back({camera, e.point});
      }
      continue;
    }
    // Slack for the float depths and rounding in the projection.
    const double depth_slack = 1e-6 * std::max(std::abs(z_min), std::abs(z_max)) + 1e-12;
    const float reach = static_cast<float>(std::max(z_min, 0.0) - depth_slack);
    if (straddles) {
      // The box contains or touches the camera plane: every ray may cross it.
      for (const auto& bucket : cb.buckets) {
        for (const Entry& e : bucket) out->push_back({camera, e.point});
      }
      for (const Entry& e : cb.overflow) out->push_back({camera, e.point});
      continue;
    }
    const auto clamp_index = [&](double value, double lo, double step) {
      return static_cast<int>(std::clamp(std::floor((value - lo) / step), -1.0,
                                         static_cast<double>(grid_)));
    };
    // One bucket of slack on each side for rounding.
    const int i0 = std::max(clamp_index(u_lo, cb.camera.u_min, cb.du) - 1, 0);
    const int i1 = std::min(clamp_index(u_hi, cb.camera.u_min, cb.du) + 1, grid_ - 1);
    const int j0 = std::max(clamp_index(v_lo, cb.camera.v_min, cb.dv) - 1, 0);
    const int j1 = std::min(clamp_index(v_hi, cb.camera.v_min, cb.dv) + 1, grid_ - 1);
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        for (const Entry& e : cb.buckets[static_cast<size_t>(j) * grid_ + i]) {
          if (e.depth >= reach) out->push_back({camera, e.point});
        }
      }
    }
    for (const Entry& e : cb.overflow) out->push_back({camera, e.point});
  }
}

size_t RayIndex::MemoryBytes() const {
  size_t bytes = 0;
  for (const CameraBuckets& cb : cameras_) {
    bytes += cb.buckets.capacity() * sizeof(std::vector<Entry>);
    for (const auto& b : cb.buckets) bytes += b.capacity() * sizeof(Entry);
    bytes += cb.overflow.capacity() * sizeof(Entry);
  }
  return bytes;
}

}  // namespace ms
