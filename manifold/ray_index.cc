#include "manifold/ray_index.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <utility>

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

// A direction's fixed-point step (Entry::qu, qv) for a value inside the grid's extent.
uint16_t FixedPoint(double value, double min, double steps_per_unit) {
  return static_cast<uint16_t>(
      std::clamp(std::floor((value - min) * steps_per_unit), 0.0, 65535.0));
}

// The steps of [lo, hi], widened by one step on each side for rounding, clamped to 0..65535;
// lo > hi when no step can be inside.
std::pair<int32_t, int32_t> FixedPointRange(double lo, double hi, double min,
                                            double steps_per_unit) {
  const double a = std::floor((lo - min) * steps_per_unit) - 1;
  const double b = std::floor((hi - min) * steps_per_unit) + 1;
  return {static_cast<int32_t>(std::clamp(a, 0.0, 65536.0)),
          static_cast<int32_t>(std::clamp(b, -1.0, 65535.0))};
}

}  // namespace

RayIndex::RayIndex(std::vector<Camera> cameras, int grid) : grid_(std::clamp(grid, 1, kMaxGrid)) {
  cameras_.resize(cameras.size());
  for (size_t c = 0; c < cameras.size(); ++c) {
    CameraBuckets& cb = cameras_[c];
    cb.camera = cameras[c];
    MS_CHECK(cb.camera.u_max > cb.camera.u_min && cb.camera.v_max > cb.camera.v_min);
    cb.su = 65536.0 / (cb.camera.u_max - cb.camera.u_min);
    cb.sv = 65536.0 / (cb.camera.v_max - cb.camera.v_min);
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

bool RayIndex::MakeEntry(const CameraBuckets& cb, int32_t point, int32_t id,
                         const Eigen::Vector3d& position, Entry* entry, OverflowEntry* overflow) {
  const Eigen::Vector3d x = cb.camera.R * (position - cb.camera.center);
  if (!(x.z() > 0)) {
    *overflow = {point, id, static_cast<float>(x.z()), 0, 0};
    return false;
  }
  const double u = x.x() / x.z(), v = x.y() / x.z();
  const Camera& k = cb.camera;
  if (u >= k.u_min && u < k.u_max && v >= k.v_min && v < k.v_max) {
    *entry = {point, id, static_cast<float>(x.z()), FixedPoint(u, k.u_min, cb.su),
              FixedPoint(v, k.v_min, cb.sv)};
    return true;
  }
  *overflow = {point, id, static_cast<float>(x.z()), static_cast<float>(u), static_cast<float>(v)};
  return false;
}

uint32_t RayIndex::BucketOf(const CameraBuckets& cb, const Entry& e) {
  const uint32_t side = static_cast<uint32_t>(cb.side);
  return ((e.qv * side) >> 16) * side + ((e.qu * side) >> 16);
}

int32_t RayIndex::Add(int32_t camera, int32_t point, const Eigen::Vector3d& position) {
  MS_CHECK(camera >= 0 && camera < num_cameras()) << camera;
  MS_CHECK(size_ < static_cast<size_t>(INT32_MAX)) << "ray index full";
  CameraBuckets& cb = cameras_[camera];
  const int32_t id = static_cast<int32_t>(size_);
  ++cb.count;
  ++size_;
  cb.lo = cb.lo.cwiseMin(position);
  cb.hi = cb.hi.cwiseMax(position);
  Entry entry;
  OverflowEntry overflow;
  if (MakeEntry(cb, point, id, position, &entry, &overflow)) {
    cb.pending.push_back(entry);
  } else {
    cb.overflow.push_back(overflow);
  }
  return id;
}

bool RayIndex::Contains(int32_t camera, int32_t point, const Eigen::Vector3d& position) const {
  MS_CHECK(camera >= 0 && camera < num_cameras()) << camera;
  const CameraBuckets& cb = cameras_[camera];
  const auto has_point = [point](const auto& e) { return e.point == point; };
  Entry probe;
  OverflowEntry overflow;
  if (!MakeEntry(cb, point, -1, position, &probe, &overflow)) {
    return std::any_of(cb.overflow.begin(), cb.overflow.end(), has_point);
  }
  if (std::any_of(cb.pending.begin(), cb.pending.end(), has_point)) return true;
  const uint32_t bucket = BucketOf(cb, probe);
  return std::any_of(cb.entries.begin() + cb.start[bucket],
                     cb.entries.begin() + cb.start[bucket + 1], has_point);
}

void RayIndex::Refile(CameraBuckets* cb, size_t rays) const {
  cb->side = std::max(cb->side, SideFor(rays));
  // Counting sort of the filed entries (in bucket order) and then the pending ones.
  const size_t buckets = static_cast<size_t>(cb->side) * cb->side;
  std::vector<uint32_t> start(buckets + 1, 0);
  for (const Entry& e : cb->entries) ++start[BucketOf(*cb, e) + 1];
  for (const Entry& e : cb->pending) ++start[BucketOf(*cb, e) + 1];
  for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
  std::vector<Entry> entries(start[buckets]);
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (const Entry& e : cb->entries) entries[fill[BucketOf(*cb, e)]++] = e;
  for (const Entry& e : cb->pending) entries[fill[BucketOf(*cb, e)]++] = e;
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
      for (const OverflowEntry& e : cb.overflow) {
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
      for (const OverflowEntry& e : cb.overflow) out->push_back({camera, e.point, e.id});
      continue;
    }
    // The box lies in front of the camera: its projection is the convex hull of its corners'
    // (a central projection keeps segments straight there), so a ray meeting it leaves the
    // camera in a direction inside [u_lo, u_hi] x [v_lo, v_hi]. Slack for rounding in the
    // projection, and for the overflow list's float coordinates.
    const double u_slack = 1e-6 * std::max({1.0, std::abs(u_lo), std::abs(u_hi)});
    const double v_slack = 1e-6 * std::max({1.0, std::abs(v_lo), std::abs(v_hi)});
    // In the grid: the fixed-point steps the rectangle covers, one more on each side.
    const Camera& k = cb.camera;
    const auto [qu_lo, qu_hi] = FixedPointRange(u_lo - u_slack, u_hi + u_slack, k.u_min, cb.su);
    const auto [qv_lo, qv_hi] = FixedPointRange(v_lo - v_slack, v_hi + v_slack, k.v_min, cb.sv);
    if (qu_lo <= qu_hi && qv_lo <= qv_hi) {
      const auto inside = [&](const Entry& e) {
        return e.depth >= reach && e.qu >= qu_lo && e.qu <= qu_hi && e.qv >= qv_lo && e.qv <= qv_hi;
      };
      // A bucket's steps are contiguous and in order, so these buckets hold every step inside.
      const uint32_t side = static_cast<uint32_t>(cb.side);
      const uint32_t i0 = (static_cast<uint32_t>(qu_lo) * side) >> 16;
      const uint32_t i1 = (static_cast<uint32_t>(qu_hi) * side) >> 16;
      const uint32_t j0 = (static_cast<uint32_t>(qv_lo) * side) >> 16;
      const uint32_t j1 = (static_cast<uint32_t>(qv_hi) * side) >> 16;
      for (uint32_t j = j0; j <= j1; ++j) {
        const size_t row = static_cast<size_t>(j) * side;
        for (uint32_t e = cb.start[row + i0]; e < cb.start[row + i1 + 1]; ++e) {
          if (inside(cb.entries[e])) {
            out->push_back({camera, cb.entries[e].point, cb.entries[e].id});
          }
        }
      }
      for (const Entry& e : cb.pending) {
        if (inside(e)) out->push_back({camera, e.point, e.id});
      }
    }
    // Overflow: directions outside the grid (tested in floats) and points at or behind the
    // camera plane (always returned).
    const float fu_lo = static_cast<float>(u_lo - u_slack),
                fu_hi = static_cast<float>(u_hi + u_slack);
    const float fv_lo = static_cast<float>(v_lo - v_slack),
                fv_hi = static_cast<float>(v_hi + v_slack);
    for (const OverflowEntry& e : cb.overflow) {
      if (!(e.depth > 0) ||
          (e.depth >= reach && e.u >= fu_lo && e.u <= fu_hi && e.v >= fv_lo && e.v <= fv_hi)) {
        out->push_back({camera, e.point, e.id});
      }
    }
  }
}

size_t RayIndex::MemoryBytes() const {
  size_t bytes = 0;
  for (const CameraBuckets& cb : cameras_) {
    bytes += cb.entries.capacity() * sizeof(Entry) + cb.start.capacity() * sizeof(uint32_t) +
             cb.pending.capacity() * sizeof(Entry);
    bytes += cb.overflow.capacity() * sizeof(OverflowEntry);
  }
  return bytes;
}

}  // namespace ms
