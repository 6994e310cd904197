#include "coordinator/job_builder.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "base/error.h"
#include "base/parallel_for.h"
#include "proto/content_hash.h"
#include "proto/options_codec.h"
#include "proto/wire.h"

namespace ms {
IterationJobs BuildIterationJobs(const Scene& scene,
                                 const std::vector<std::vector<int>>& neighbours, const Mesh& mesh,
                                 const ImageCatalog& images, uint32_t iteration,
                                 uint64_t session_id, const JobBuildOptions& options) {
  IterationJobs result;
  auto set_image = [&](int v, wire::JobCamera* camera) {
    const ImageRecord& record = images.view(v);
    wire::ImageRef* ref = camera->mutable_image();
    ref->set_path(record.path);
    ref->set_content_hash(record.hash);
    ref->set_byte_size(record.size);
  };
  // Cameras are independent: build their jobs in parallel, then collect them in camera order.
  const VisibleMeshIndex index(mesh);
  struct CameraJob {
    std::optional<wire::Job> job;
    std::string skipped;
    size_t faces = 0;
    uint64_t bytes = 0;
  };
  std::vector<CameraJob> built(scene.views.size());
  ParallelFor(scene.views.size(), [&](size_t c) {
    CameraJob& out = built[c];
    if (neighbours[c].empty()) {
      out.skipped = fmt::format("camera {}: no neighbour", c);
      return;
    }
    const VisibleMesh visible = index.Extract(scene.views[c], options.visible);
    if (visible.mesh.faces.empty()) {
      out.skipped = fmt::format("camera {}: sees no face of the mesh", c);
      return;
    }
    wire::Job& job = out.job.emplace();
    job.set_job_id(MakeJobId(iteration, static_cast<uint32_t>(c)));
    job.set_iteration(iteration);
    job.set_session_id(session_id);
    ViewToWire(static_cast<int32_t>(c), scene.views[c], job.mutable_camera());
    set_image(static_cast<int>(c), job.mutable_camera());
    for (int n : neighbours[c]) {
      wire::JobCamera* camera = job.add_neighbours();
      ViewToWire(n, scene.views[n], camera);
      set_image(n, camera);
    }
    PackMesh(visible.mesh, job.mutable_mesh());
    OptionsToWire(options.sweep, job.mutable_options());
    job.set_lease_seconds(options.lease_s);
    const uint64_t bytes = job.ByteSizeLong();
    // Leave room for the envelope around the job.
    if (bytes + 1024 > options.limits.max_message_bytes) {
      throw InputError(fmt::format(
          "the job of camera {} ({} visible faces) is {} bytes, over the message limit of {} "
          "bytes: raise --max-message-mb on the coordinator and the workers",
          c, visible.mesh.NumFaces(), bytes, options.limits.max_message_bytes));
    }
    out.faces = visible.mesh.NumFaces();
    out.bytes = bytes;
  });
  for (CameraJob& camera : built) {
    if (!camera.job) {
      result.skipped.push_back(std::move(camera.skipped));
      continue;
    }
    result.faces += static_cast<int64_t>(camera.faces);
    result.bytes += camera.bytes;
    result.max_bytes = std::max(result.max_bytes, camera.bytes);
    result.jobs.push_back(std::move(*camera.job));
  }
  return result;
}

}  // namespace ms
