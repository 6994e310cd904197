#include "coordinator/job_builder.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "base/check.h"
#include "base/error.h"
#include "base/log.h"
#include "base/parallel_for.h"
#include "proto/content_hash.h"
#include "proto/options_codec.h"
#include "proto/wire.h"

namespace ms {

IterationJobSource::IterationJobSource(const Scene& scene,
                                       const std::vector<std::vector<int>>& neighbours,
                                       std::shared_ptr<const Mesh> mesh, const ImageCatalog& images,
                                       uint32_t iteration, uint64_t session_id,
                                       const JobBuildOptions& options)
    : scene_(scene),
      neighbours_(neighbours),
      mesh_(std::move(mesh)),
      images_(images),
      iteration_(iteration),
      session_id_(session_id),
      options_(options),
      index_(*mesh_),
      counted_(scene.views.size(), false) {
  MS_CHECK(neighbours.size() == scene.views.size()) << "one neighbour list per camera";
  MS_CHECK(options.swept.empty() || options.swept.size() == scene.views.size());
  for (size_t c = 0; c < scene.views.size(); ++c) {
    if (!options.swept.empty() && !options.swept[c]) continue;
    if (neighbours[c].empty()) {
      stats_.skipped.push_back(fmt::format("camera {}: no neighbour", c));
    } else {
      job_ids_.push_back(MakeJobId(iteration, static_cast<uint32_t>(c)));
    }
  }
}

std::optional<BuiltJob> IterationJobSource::BuildOne(int c, std::string* skipped) const {
  const VisibleMesh visible = index_.Extract(scene_.views[c], options_.visible);
  if (visible.mesh.faces.empty()) {
    *skipped = fmt::format("camera {}: sees no face of the mesh", c);
    return std::nullopt;
  }
  auto set_image = [&](int v, wire::JobCamera* camera) {
    const ImageRecord& record = images_.view(v);
    wire::ImageRef* ref = camera->mutable_image();
    ref->set_path(record.path);
    ref->set_content_hash(record.hash);
    ref->set_byte_size(record.size);
  };
  std::optional<BuiltJob> out;
  wire::Job& job = out.emplace().job;
  job.set_job_id(MakeJobId(iteration_, static_cast<uint32_t>(c)));
  job.set_iteration(iteration_);
  job.set_session_id(session_id_);
  ViewToWire(c, scene_.views[c], job.mutable_camera());
  set_image(c, job.mutable_camera());
  for (int n : neighbours_[c]) {
    wire::JobCamera* camera = job.add_neighbours();
    ViewToWire(n, scene_.views[n], camera);
    set_image(n, camera);
  }
  PackMesh(visible.mesh, job.mutable_mesh());
  OptionsToWire(options_.sweep, job.mutable_options());
  job.set_lease_seconds(options_.lease_s);
  const uint64_t bytes = job.ByteSizeLong();
  // Leave room for the envelope around the job.
  if (bytes + 1024 > options_.limits.max_message_bytes) {
    throw InputError(fmt::format(
        "the job of camera {} ({} visible faces) is {} bytes, over the message limit of {} "
        "bytes: raise --max-message-mb on the coordinator and the workers",
        c, visible.mesh.NumFaces(), bytes, options_.limits.max_message_bytes));
  }
  out->bytes = bytes;
  out->bounds = JobBoundsFromWire(job, visible.mesh);
  return out;
}

std::vector<std::optional<BuiltJob>> IterationJobSource::Build(const std::vector<uint64_t>& ids,
                                                               int threads) {
  Timer timer;
  std::vector<int> cameras;
  for (uint64_t id : ids) {
    const int c = static_cast<int>(JobIdCamera(id));
    MS_CHECK(JobIdIteration(id) == iteration_ && c >= 0 &&
             c < static_cast<int>(scene_.views.size()) && !neighbours_[c].empty() &&
             (options_.swept.empty() || options_.swept[c]))
        << "job " << id << " is not one of this iteration's";
    cameras.push_back(c);
  }
  std::vector<std::optional<BuiltJob>> jobs(ids.size());
  std::vector<std::string> skipped(ids.size());
  const auto build = [&](size_t i) { jobs[i] = BuildOne(cameras[i], &skipped[i]); };
  // Cameras are independent; one job (the usual case once the sweep runs) stays on this thread.
  if (ids.size() == 1 || threads == 1) {
    for (size_t i = 0; i < ids.size(); ++i) build(i);
  } else {
    ParallelFor(ids.size(), build, threads);
  }
  const std::lock_guard<std::mutex> lock(stats_mutex_);
  for (size_t i = 0; i < ids.size(); ++i) {
    if (counted_[cameras[i]]) continue;
    counted_[cameras[i]] = true;
    if (!jobs[i]) {
      stats_.skipped.push_back(std::move(skipped[i]));
      continue;
    }
    ++stats_.jobs;
    stats_.faces += jobs[i]->job.mesh().num_faces();
    stats_.bytes += jobs[i]->bytes;
    stats_.max_bytes = std::max(stats_.max_bytes, jobs[i]->bytes);
  }
  stats_.seconds += timer.Seconds();
  return jobs;
}

std::vector<wire::Job> IterationJobSource::BuildAll() {
  std::vector<wire::Job> all;
  for (std::optional<BuiltJob>& built : Build(job_ids_)) {
    if (built) all.push_back(std::move(built->job));
  }
  return all;
}

JobBuildStats IterationJobSource::stats() const {
  const std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

}  // namespace ms
