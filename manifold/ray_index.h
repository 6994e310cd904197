// Finds the viewing rays (camera -> point segments) that may cross a box, without storing
// per-cell ray lists: per camera, rays are bucketed by the direction they leave the camera
// (normalised image coordinates x/z, y/z) and keep that direction and the depth of their end
// point. A query projects the box into each camera and returns the rays of the covered
// buckets whose direction lies in the projection's bounding rectangle and that reach the
// box's nearest depth. Conservative: it may return rays that miss the box, never omits one
// that hits it.
//
// Scale (docs/design/scalability.md): each camera's grid grows with its rays (about kRaysPerBucket
// a bucket, up to `grid` per side), so thousands of cameras with a few thousand rays each do not
// each hold a full grid; and a query skips every camera whose rays' bounding box (the camera
// centre and the end points) misses the box, so its cost follows the cameras near the box, not
// all of them.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <vector>

namespace ms {

struct RayRef {
  int32_t camera;
  int32_t point;
  int32_t id = -1;  // the index's number for the ray (Add's answer); not part of comparisons
  bool operator<(const RayRef& o) const {
    return camera != o.camera ? camera < o.camera : point < o.point;
  }
  bool operator==(const RayRef& o) const { return camera == o.camera && point == o.point; }
};

class RayIndex {
 public:
  struct Camera {
    Eigen::Matrix3d R;       // world -> camera
    Eigen::Vector3d center;  // camera centre in world coordinates
    // Extent of normalised coordinates covered by buckets (e.g. the image's frustum);
    // rays outside go to an overflow list that every query returns.
    double u_min = -1, u_max = 1, v_min = -1, v_max = 1;
  };

  // `grid`: the most buckets per side of a camera's grid.
  RayIndex(std::vector<Camera> cameras, int grid = 128);
  // Filed rays per bucket a camera's grid aims at before it doubles its side.
  static constexpr size_t kRaysPerBucket = 4;
  // At most 65,536 buckets per side: a bucket holds whole fixed-point steps.
  static constexpr int kMaxGrid = 1 << 16;

  // Returns the ray's id: rays are numbered 0, 1, ... in the order they are added. Added rays
  // wait in a short list that queries scan whole until Flush files them into the buckets:
  // add a batch, then flush.
  int32_t Add(int32_t camera, int32_t point, const Eigen::Vector3d& position);
  void Flush();
  // Whether the ray camera -> point is in the index; `position` must be the one it was added
  // with (its direction finds the bucket).
  bool Contains(int32_t camera, int32_t point, const Eigen::Vector3d& position) const;
  // Appends to `out` every ray that may intersect the closed box [min, max].
  void Query(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
             std::vector<RayRef>* out) const;
  // Calls visit(ray) for every ray, camera by camera and, within a camera, by direction
  // (buckets in Morton order): consecutive rays leave the same camera side by side, so walks
  // along them in this order cross mostly the same cells, which stay in cache.
  template <typename Visit>
  void ForEachInDirectionOrder(Visit&& visit) const;
  // The same order, handed to visit(const std::vector<RayRef>&) `chunk` rays at a time (the last
  // chunk may be shorter), for callers that work on many rays at once without a list of all.
  template <typename Visit>
  void ForEachChunkInDirectionOrder(size_t chunk, Visit&& visit) const;

  size_t size() const { return size_; }
  size_t MemoryBytes() const;
  int num_cameras() const { return static_cast<int>(cameras_.size()); }

 private:
  // A ray in a camera's grid: its direction as 16-bit fixed point across the grid's extent
  // (16 bytes against 20 with floats; 10 rays a point make this the index's size).
  struct Entry {
    int32_t point;
    int32_t id;
    float depth;      // camera-frame z of the end point
    uint16_t qu, qv;  // floor(65536 (u - u_min) / (u_max - u_min)), the same for v
  };
  // A ray outside the grid's extent, or ending at or behind the camera plane.
  struct OverflowEntry {
    int32_t point;
    int32_t id;
    float depth;
    float u, v;  // its normalised image coordinates (direction from the camera)
  };
  struct CameraBuckets {
    Camera camera;
    int side = 1;  // buckets per side: a power of two, or grid_
    // Fixed-point steps per unit of u and v: 65536 / (u_max - u_min), 65536 / (v_max - v_min).
    double su = 1, sv = 1;
    // Bucket b (row-major, side x side) is entries[start[b], start[b + 1]): a query's rows of
    // buckets are contiguous runs.
    std::vector<Entry> entries;
    std::vector<uint32_t> start{0, 0};
    std::vector<Entry> pending;           // inside the grid, until Flush files them
    std::vector<OverflowEntry> overflow;  // outside the grid, or at depth <= 0
    size_t count = 0;
    // Box of the camera centre and every end point: it holds every ray of the camera.
    Eigen::Vector3d lo, hi;
  };
  // The entry Add files for a ray: false for a ray that goes to the overflow list (then in
  // *overflow), true for one in the grid (in *entry).
  static bool MakeEntry(const CameraBuckets& cb, int32_t point, int32_t id,
                        const Eigen::Vector3d& position, Entry* entry, OverflowEntry* overflow);
  // The bucket of an entry: from its fixed-point direction only, so filing and queries agree.
  static uint32_t BucketOf(const CameraBuckets& cb, const Entry& e);
  // Sets cb's side for `rays` filed rays (it only grows) and files entries and pending anew.
  void Refile(CameraBuckets* cb, size_t rays) const;
  int SideFor(size_t rays) const;
  const std::vector<uint32_t>& MortonOrder(int side) const;

  std::vector<CameraBuckets> cameras_;
  int grid_;
  // Bucket indices in Morton order, per side (1, 2, 4, ... and grid_).
  std::vector<std::pair<int, std::vector<uint32_t>>> morton_;
  size_t size_ = 0;
};

template <typename Visit>
void RayIndex::ForEachInDirectionOrder(Visit&& visit) const {
  for (size_t c = 0; c < cameras_.size(); ++c) {
    const CameraBuckets& cb = cameras_[c];
    const int32_t camera = static_cast<int32_t>(c);
    for (uint32_t bucket : MortonOrder(cb.side)) {
      for (uint32_t k = cb.start[bucket]; k < cb.start[bucket + 1]; ++k) {
        visit(RayRef{camera, cb.entries[k].point, cb.entries[k].id});
      }
    }
    for (const Entry& e : cb.pending) visit(RayRef{camera, e.point, e.id});
    for (const OverflowEntry& e : cb.overflow) visit(RayRef{camera, e.point, e.id});
  }
}

template <typename Visit>
void RayIndex::ForEachChunkInDirectionOrder(size_t chunk, Visit&& visit) const {
  std::vector<RayRef> rays;
  rays.reserve(std::min(chunk, size_));
  ForEachInDirectionOrder([&](const RayRef& ray) {
    rays.push_back(ray);
    if (rays.size() < chunk) return;
    visit(static_cast<const std::vector<RayRef>&>(rays));
    rays.clear();
  });
  if (!rays.empty()) visit(static_cast<const std::vector<RayRef>&>(rays));
}

}  // namespace ms
