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
#include "mesh/mesh.h"
#include "proto/manisweep.pb.h"
#include "scene/camera.h"

namespace ms {

// A point returned by a worker, validated.
struct FoundPoint {
  int32_t camera = 0;
  float pixel_x = 0, pixel_y = 0;
  int32_t offset = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  std::vector<int32_t> cameras;
};

// What a result is checked against: the job as it was handed out.
struct JobBounds {
  int32_t camera = -1;
  std::vector<int32_t> cameras;  // C, then its neighbours: the only ids a point may list
  View view;                     // C, full resolution (the sweep's pixels are undistorted)
  // Camera z a swept point can have: the visible mesh's vertices' range widened by the largest
  // move of the sweep, K alpha (alpha: the job's, or the automatic alpha's bound of 0.02 x the
  // median vertex depth).
  double min_depth = 0, max_depth = 0;
};

// The bounds of a job; throws InputError for a malformed job (the coordinator built it).
JobBounds JobBoundsFromWire(const wire::Job& job);
// The same, with the job's mesh given unpacked (the job builder has it: no second unpacking).
JobBounds JobBoundsFromWire(const wire::Job& job, const Mesh& mesh);

// A reported point's pixel and its projection into C may differ by this much (pixels): the
// GLSL kernel places points in float32.
constexpr double kPixelTolerance = 0.5;

// The points of `result`, a result of the job `job`, into *points. Returns "" if every point is
// usable, else the first problem (the result is then dropped whole): a non-finite value; a point
// that does not list C first, lists a camera twice or one that is not C or its neighbours; a
// pixel outside C's image; a position that does not project to its pixel (within
// kPixelTolerance) or lies outside the swept depth range. A worker can thus only return points
// of the kind the sweep of that job could find (docs/design/distributed.md).
std::string ValidateResultPoints(const wire::Result& result, const JobBounds& job,
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

  // True once the result (or the refusal) of job `job_id` is recorded.
  bool Has(uint64_t job_id) const { return by_job_.count(job_id) > 0; }

  // The points in insertion order: by camera, pixel row, column, then every other field, so the
  // order is total and the same whatever the arrival order.
  std::vector<RayPoint> Sorted() const;
  // The points of these jobs only, in insertion order. Camera comes first in that order, so for
  // consecutive runs of jobs in camera order the parts, one after the other, are Sorted().
  std::vector<RayPoint> SortedOf(const std::vector<uint64_t>& job_ids) const;

 private:
  std::map<uint64_t, std::vector<FoundPoint>> by_job_;
  int64_t num_points_ = 0;
};

}  // namespace ms
