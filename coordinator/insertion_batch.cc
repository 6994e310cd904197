#include "coordinator/insertion_batch.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

namespace ms {
namespace {

bool InsertionOrder(const FoundPoint& a, const FoundPoint& b) {
  return std::tie(a.camera, a.pixel_y, a.pixel_x, a.offset, a.position.x(), a.position.y(),
                  a.position.z(), a.cameras) < std::tie(b.camera, b.pixel_y, b.pixel_x, b.offset,
                                                        b.position.x(), b.position.y(),
                                                        b.position.z(), b.cameras);
}

}  // namespace

std::string ValidateResultPoints(const wire::Result& result, int32_t camera, int32_t num_views,
                                 std::vector<FoundPoint>* points) {
  for (int i = 0; i < result.points_size(); ++i) {
    const wire::SweepPoint& p = result.points(i);
    FoundPoint f;
    f.camera = camera;
    f.pixel_x = p.pixel_x();
    f.pixel_y = p.pixel_y();
    f.offset = p.offset();
    f.position = Eigen::Vector3d(p.x(), p.y(), p.z());
    if (!f.position.allFinite() || !std::isfinite(f.pixel_x) || !std::isfinite(f.pixel_y)) {
      return fmt::format("point {} is not finite", i);
    }
    if (p.cameras_size() < 1 || p.cameras(0) != camera) {
      return fmt::format("point {} does not list camera {} first", i, camera);
    }
    std::set<int32_t> seen;
    for (int32_t c : p.cameras()) {
      if (c < 0 || c >= num_views || !seen.insert(c).second) {
        return fmt::format("point {} lists camera {} (twice, or not in the scene)", i, c);
      }
      f.cameras.push_back(c);
    }
    points->push_back(std::move(f));
  }
  return "";
}

bool InsertionBatch::Add(uint64_t job_id, std::vector<FoundPoint> points) {
  const int64_t n = static_cast<int64_t>(points.size());
  if (!by_job_.emplace(job_id, std::move(points)).second) return false;
  num_points_ += n;
  return true;
}

std::vector<RayPoint> InsertionBatch::Sorted() const {
  std::vector<const FoundPoint*> found;
  found.reserve(static_cast<size_t>(num_points_));
  for (const auto& [id, points] : by_job_) {
    for (const FoundPoint& p : points) found.push_back(&p);
  }
  std::sort(found.begin(), found.end(),
            [](const FoundPoint* a, const FoundPoint* b) { return InsertionOrder(*a, *b); });
  std::vector<RayPoint> batch;
  batch.reserve(found.size());
  for (const FoundPoint* p : found) {
    RayPoint r;
    r.position = p->position;
    r.cameras = p->cameras;
    batch.push_back(std::move(r));
  }
  return batch;
}

}  // namespace ms
