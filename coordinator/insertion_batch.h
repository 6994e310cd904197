// The points of one iteration, from the workers' results to the manifold's batch: each result
// checked against its job, the first result of a job kept, and the whole sorted by (camera,
// pixel, ...) so the batch does not depend on which worker delivered what, or when.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "manifold/delaunay_manifold.h"
#include "proto/manisweep.pb.h"

namespace ms {

// A point returned by a worker, validated.
struct FoundPoint {
  int32_t camera = 0;
  float pixel_x = 0, pixel_y = 0;
  int32_t offset = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  std::vector<int32_t> cameras;
};

// The points of `result`, a result of the job of `camera`, into *points. Returns "" if every
// point is usable, else the first problem (the result is then dropped whole): a non-finite
// value, a point that does not list `camera` first, a camera listed twice or not in the scene
// (num_views views).
std::string ValidateResultPoints(const wire::Result& result, int32_t camera, int32_t num_views,
                                 std::vector<FoundPoint>* points);

class InsertionBatch {
 public:
  // Records the points of job `job_id`. Only the first result of a job counts: a later one
  // (a duplicate delivery) is ignored and false is returned.
  bool Add(uint64_t job_id, std::vector<FoundPoint> points);
  // Records that job `job_id` gives no point (its kernel refused it).
  bool AddEmpty(uint64_t job_id) { return Add(job_id, {}); }

  int64_t num_points() const { return num_points_; }
  size_t num_jobs() const { return by_job_.size(); }

  // The points in insertion order: by camera, pixel row, column, then every other field, so the
  // order is total and the same whatever the arrival order.
  std::vector<RayPoint> Sorted() const;

 private:
  std::map<uint64_t, std::vector<FoundPoint>> by_job_;
  int64_t num_points_ = 0;
};

}  // namespace ms
