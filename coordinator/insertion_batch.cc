#include "coordinator/insertion_batch.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include "proto/wire.h"

namespace ms {
namespace {

bool InsertionOrder(const FoundPoint& a, const FoundPoint& b) {
  return std::tie(a.camera, a.pixel_y, a.pixel_x, a.offset, a.position.x(), a.position.y(),
                  a.position.z(), a.cameras) < std::tie(b.camera, b.pixel_y, b.pixel_x, b.offset,
                                                        b.position.x(), b.position.y(),
                                                        b.position.z(), b.cameras);
}

}  // namespace

JobBounds JobBoundsFromWire(const wire::Job& job) {
  return JobBoundsFromWire(job, UnpackMesh(job.mesh(), fmt::format("job {}", job.job_id())));
}

JobBounds JobBoundsFromWire(const wire::Job& job, const Mesh& mesh) {
  JobBounds b;
  b.camera = job.camera().id();
  b.cameras.push_back(b.camera);
  for (const wire::JobCamera& n : job.neighbours()) b.cameras.push_back(n.id());
  b.view = ViewFromWire(job.camera(), fmt::format("job {}", job.job_id()));
  std::vector<double> depths;
  for (const Eigen::Vector3d& v : mesh.vertices) depths.push_back(b.view.ToCamera(v).z());
  if (depths.empty()) return b;  // no point can fit
  std::sort(depths.begin(), depths.end());
  const double median = std::max(0.0, depths[depths.size() / 2]);
  const int k_max = std::max(0, (job.options().num_offsets() - 1) / 2);
  const double alpha = job.options().alpha() > 0 ? job.options().alpha() : 0.02 * median;
  const double reach = k_max * alpha;
  b.min_depth = std::max(0.0, depths.front() - reach);
  b.max_depth = depths.back() + reach;
  return b;
}

std::string ValidateResultPoints(const wire::Result& result, const JobBounds& job,
                                 std::vector<FoundPoint>* points) {
  const Intrinsics& k = job.view.intrinsics;
  for (int i = 0; i < result.points_size(); ++i) {
    const wire::SweepPoint& p = result.points(i);
    FoundPoint f;
    f.camera = job.camera;
    f.pixel_x = p.pixel_x();
    f.pixel_y = p.pixel_y();
    f.offset = p.offset();
    f.position = Eigen::Vector3d(p.x(), p.y(), p.z());
    if (!f.position.allFinite() || !std::isfinite(f.pixel_x) || !std::isfinite(f.pixel_y)) {
      return fmt::format("point {} is not finite", i);
    }
    if (p.cameras_size() < 1 || p.cameras(0) != job.camera) {
      return fmt::format("point {} does not list camera {} first", i, job.camera);
    }
    std::set<int32_t> seen;
    for (int32_t c : p.cameras()) {
      if (std::find(job.cameras.begin(), job.cameras.end(), c) == job.cameras.end() ||
          !seen.insert(c).second) {
        return fmt::format("point {} lists camera {} (twice, or not one of the job's)", i, c);
      }
      f.cameras.push_back(c);
    }
    if (!(f.pixel_x >= 0 && f.pixel_x <= k.width && f.pixel_y >= 0 && f.pixel_y <= k.height)) {
      return fmt::format("point {}: pixel ({}, {}) is outside camera {}'s {}x{} image", i,
                         f.pixel_x, f.pixel_y, job.camera, k.width, k.height);
    }
    const Eigen::Vector3d x = job.view.ToCamera(f.position);
    if (!(x.z() >= job.min_depth && x.z() <= job.max_depth)) {
      return fmt::format(
          "point {}: depth {:.6g} in camera {} is outside the swept range "
          "[{:.6g}, {:.6g}]",
          i, x.z(), job.camera, job.min_depth, job.max_depth);
    }
    const double u = k.fx * x.x() / x.z() + k.cx, v = k.fy * x.y() / x.z() + k.cy;
    if (std::hypot(u - f.pixel_x, v - f.pixel_y) > kPixelTolerance) {
      return fmt::format(
          "point {} projects to ({:.2f}, {:.2f}) in camera {}, not to its pixel "
          "({:.2f}, {:.2f})",
          i, u, v, job.camera, f.pixel_x, f.pixel_y);
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
  std::vector<uint64_t> all;
  for (const auto& [id, points] : by_job_) all.push_back(id);
  return SortedOf(all);
}

std::vector<RayPoint> InsertionBatch::SortedOf(const std::vector<uint64_t>& job_ids) const {
  std::vector<const FoundPoint*> found;
  for (uint64_t id : job_ids) {
    auto it = by_job_.find(id);
    if (it == by_job_.end()) continue;
    for (const FoundPoint& p : it->second) found.push_back(&p);
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
