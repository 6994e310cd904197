#include "manifold/ray_index.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include "base/check.h"

namespace ms {

namespace {

// Bucket indices of a side x side grid (row-major) in Morton (Z) order.
std::vector<uint32_t> MortonBuckets(int side) {
  std::vector<std::pair<uint64_t, uint32_t>> keyed;
  for (uint32_t j = 0; j < static_cast<uint32_t>(side); ++j) {
    for (uint32_t i = 0; i < static_cast<uint32_t>(side); ++i) {
      uint64_t key = 0;
      for (int bit = 0; bit < 16; ++bit) {
        key |= static_cast<uint64_t>((i >> bit) & 1) << (2 * bit);
        key |= static_cast<uint64_t>((j >> bit) & 1) << (2 * bit + 1);
      }
      keyed.push_back({key, j * side + i});
    }
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<uint32_t> order;
  for (const auto& [key, bucket] : keyed) order.push_back(bucket);
  return order;
}

}  // namespace

RayIndex::RayIndex(std::vector<Camera> cameras, int grid) : grid_(std::max(grid, 1)) {
  cameras_.resize(cameras.size());
  for (size_t c = 0; c < cameras.size(); ++c) {
    CameraBuckets& cb = cameras_[c];
    cb.camera = cameras[c];
    MS_CHECK(cb.camera.u_max > cb.camera.u_min && cb.camera.v_max > cb.camera.v_min);
    cb.du = cb.camera.u_max - cb.camera.u_min;
    cb.dv = cb.camera.v_max - cb.camera.v_min;
    cb.lo = cb.hi = cb.camera.center;
  }
  for (int side = 1;; side *= 2) {
    morton_.emplace_back(std::min(side, grid_), MortonBuckets(std::min(side, grid_)));
    if (side >= grid_) break;
  }
}

int RayIndex::SideFor(size_t rays) const {
  int side = 1;
  while (side < grid_ && static_cast<size_t>(side) * side * kRaysPerBucket < rays) side *= 2;
  return std::min(side, grid_);
}

const std::vector<uint32_t>& RayIndex::MortonOrder(int side) const {
  for (const auto& [s, order] : morton_) {
    if (s == side) return order;
  }
  MS_CHECK(false) << "no Morton order for side " << side;
  return morton_.front().second;
}

int32_t RayIndex::Add(int32_t camera, int32_t point, const Eigen::Vector3d& position) {
  MS_CHECK(camera >= 0 && camera < num_cameras()) << camera;
  MS_CHECK(size_ < static_cast<size_t>(INT32_MAX)) << "ray index full";
  CameraBuckets& cb = cameras_[camera];
  const Eigen::Vector3d x = cb.camera.R * (position - cb.camera.center);
  const int32_t id = static_cast<int32_t>(size_);
  ++cb.count;
  ++size_;
  cb.lo = cb.lo.cwiseMin(position);
  cb.hi = cb.hi.cwiseMax(position);
  if (!(x.z() > 0)) {
    cb.overflow.push_back({point, id, static_cast<float>(x.z()), 0, 0});
    return id;
  }
  const double u = x.x() / x.z(), v = x.y() / x.z();
  const Entry entry{point, id, static_cast<float>(x.z()), static_cast<float>(u),
                    static_cast<float>(v)};
  const Camera& k = cb.camera;
  if (u >= k.u_min && u < k.u_max && v >= k.v_min && v < k.v_max) {
    cb.pending.push_back(entry);
  } else {
    cb.overflow.push_back(entry);
  }
  return id;
}

void RayIndex::Refile(CameraBuckets* cb, size_t rays) const {
  cb->side = std::max(cb->side, SideFor(rays));
  cb->du = (cb->camera.u_max - cb->camera.u_min) / cb->side;
  cb->dv = (cb->camera.v_max - cb->camera.v_min) / cb->side;
  // From the float direction: within one bucket of the double one, which queries allow for.
  const auto bucket_of = [cb](const Entry& e) {
    const int side = cb->side;
    const int i =
        std::clamp(static_cast<int>(std::floor((e.u - cb->camera.u_min) / cb->du)), 0, side - 1);
    const int j =
        std::clamp(static_cast<int>(std::floor((e.v - cb->camera.v_min) / cb->dv)), 0, side - 1);
    return static_cast<uint32_t>(j) * side + static_cast<uint32_t>(i);
  };
  // Counting sort of the filed entries (in bucket order) and then the pending ones.
  const size_t buckets = static_cast<size_t>(cb->side) * cb->side;
  std::vector<uint32_t> start(buckets + 1, 0);
  for (const Entry& e : cb->entries) ++start[bucket_of(e) + 1];
  for (const Entry& e : cb->pending) ++start[bucket_of(e) + 1];
  for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
  std::vector<Entry> entries(start[buckets]);
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (const Entry& e : cb->entries) entries[fill[bucket_of(e)]++] = e;
  for (const Entry& e : cb->pending) entries[fill[bucket_of(e)]++] = e;
  cb->entries = std::move(entries);
  cb->start = std::move(start);
  cb->pending.clear();
  cb->pending.shrink_to_fit();
}

void RayIndex::Flush() {
  for (CameraBuckets& cb : cameras_) {
    if (cb.pending.empty()) continue;
    MS_CHECK(cb.entries.size() + cb.pending.size() < UINT32_MAX) << "ray index overflow";
    Refile(&cb, cb.entries.size() + cb.pending.size());
  }
}

void RayIndex::Query(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                     std::vector<RayRef>* out) const {
  for (size_t c = 0; c < cameras_.size(); ++c) {
    const CameraBuckets& cb = cameras_[c];
    if (cb.count == 0) continue;
    // Every ray of the camera lies in [cb.lo, cb.hi]: a box apart from it meets none. Slack
    // far above rounding, so the segment tests callers run afterwards cannot disagree.
    const double box_slack =
        1e-9 * std::max({cb.lo.cwiseAbs().maxCoeff(), cb.hi.cwiseAbs().maxCoeff(),
                         min.cwiseAbs().maxCoeff(), max.cwiseAbs().maxCoeff()});
    if ((min.array() > cb.hi.array() + box_slack).any() ||
        (max.array() < cb.lo.array() - box_slack).any()) {
      continue;
    }
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
        if (e.depth <= 0) out->push_back({camera, e.point, e.id});
      }
      continue;
    }
    // Slack for the float depths and rounding in the projection.
    const double depth_slack = 1e-6 * std::max(std::abs(z_min), std::abs(z_max)) + 1e-12;
    const float reach = static_cast<float>(std::max(z_min, 0.0) - depth_slack);
    if (straddles) {
      // The box contains or touches the camera plane: every ray may cross it.
      for (const Entry& e : cb.entries) out->push_back({camera, e.point, e.id});
      for (const Entry& e : cb.pending) out->push_back({camera, e.point, e.id});
      for (const Entry& e : cb.overflow) out->push_back({camera, e.point, e.id});
      continue;
    }
    const int side = cb.side;
    const auto clamp_index = [&](double value, double lo, double step) {
      return static_cast<int>(
          std::clamp(std::floor((value - lo) / step), -1.0, static_cast<double>(side)));
    };
    // The box lies in front of the camera: its projection is the convex hull of its corners'
    // (a central projection keeps segments straight there), so a ray meeting it leaves the
    // camera in a direction inside [u_lo, u_hi] x [v_lo, v_hi]. Slack for the float
    // coordinates and rounding in the projection.
    const double u_slack = 1e-6 * std::max({1.0, std::abs(u_lo), std::abs(u_hi)});
    const double v_slack = 1e-6 * std::max({1.0, std::abs(v_lo), std::abs(v_hi)});
    const float fu_lo = static_cast<float>(u_lo - u_slack),
                fu_hi = static_cast<float>(u_hi + u_slack);
    const float fv_lo = static_cast<float>(v_lo - v_slack),
                fv_hi = static_cast<float>(v_hi + v_slack);
    const auto inside = [&](const Entry& e) {
      return e.depth >= reach && e.u >= fu_lo && e.u <= fu_hi && e.v >= fv_lo && e.v <= fv_hi;
    };
    // One bucket of slack on each side for rounding in the bucket index.
    const int i0 = std::max(clamp_index(u_lo, cb.camera.u_min, cb.du) - 1, 0);
    const int i1 = std::min(clamp_index(u_hi, cb.camera.u_min, cb.du) + 1, side - 1);
    const int j0 = std::max(clamp_index(v_lo, cb.camera.v_min, cb.dv) - 1, 0);
    const int j1 = std::min(clamp_index(v_hi, cb.camera.v_min, cb.dv) + 1, side - 1);
    for (int j = j0; j <= j1; ++j) {
      const size_t row = static_cast<size_t>(j) * side;
      for (uint32_t k = cb.start[row + i0]; k < cb.start[row + i1 + 1]; ++k) {
        if (inside(cb.entries[k])) out->push_back({camera, cb.entries[k].point, cb.entries[k].id});
      }
    }
    for (const Entry& e : cb.pending) {
      if (inside(e)) out->push_back({camera, e.point, e.id});
    }
    // Overflow: directions outside the grid (tested like the others) and points at or behind
    // the camera plane (always returned).
    for (const Entry& e : cb.overflow) {
      if (!(e.depth > 0) || inside(e)) out->push_back({camera, e.point, e.id});
    }
  }
}

size_t RayIndex::MemoryBytes() const {
  size_t bytes = 0;
  for (const CameraBuckets& cb : cameras_) {
    bytes += cb.entries.capacity() * sizeof(Entry) + cb.start.capacity() * sizeof(uint32_t) +
             cb.pending.capacity() * sizeof(Entry);
    bytes += cb.overflow.capacity() * sizeof(Entry);
  }
  return bytes;
}

}  // namespace ms
