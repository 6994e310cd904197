// Sweep jobs for one iteration: one per camera, with its neighbours, the part of the current
// mesh it sees, the sweep options, and references to the image files (path, size, content
// hash) that workers read directly or fetch from the coordinator (image_catalog.h).
//
// Jobs are built when they are handed out, not all at once: an iteration's jobs together are
// about half as large as the manifold (docs/design/scalability.md, "Memory per point"), and
// building them while the first ones are swept takes the building off the coordinator's serial
// path. A job is a function of the iteration's mesh and the scene only, so a job built again (its
// lease expired, its worker died) is the same message.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "coordinator/image_catalog.h"
#include "coordinator/insertion_batch.h"
#include "mesh/mesh.h"
#include "mesh/visible_mesh.h"
#include "proto/manisweep.pb.h"
#include "proto/wire_limits.h"
#include "scene/scene.h"
#include "scene/view_selection.h"
#include "sweep/sweep_options.h"

namespace ms {

struct JobBuildOptions {
  VisibleMeshOptions visible;
  SweepOptions sweep;
  double lease_s = 600;
  WireLimits limits;
  // The cameras that get jobs (1 each); empty: every camera (an extension sweeps only its new
  // cameras and their neighbours).
  std::vector<uint8_t> swept;
};

// A job as it goes out, with what its result must fit and its serialized size.
struct BuiltJob {
  wire::Job job;
  JobBounds bounds;
  uint64_t bytes = 0;
};

// What the jobs built so far add up to (each job counted once, however often it was built).
struct JobBuildStats {
  int64_t jobs = 0;                  // built with faces
  int64_t faces = 0;                 // visible faces over those jobs
  uint64_t bytes = 0;                // serialized size of those jobs
  uint64_t max_bytes = 0;            // of the largest
  double seconds = 0;                // wall time spent building
  std::vector<std::string> skipped;  // "camera 3: no neighbour" ... in the order found
};

class IterationJobSource {
 public:
  // Keeps references to scene, neighbours and images, which must outlive the source and stay
  // unchanged; shares the mesh (the iteration's surface, which the coordinator replaces when
  // the iteration ends).
  IterationJobSource(const Scene& scene, const std::vector<std::vector<int>>& neighbours,
                     std::shared_ptr<const Mesh> mesh, const ImageCatalog& images,
                     uint32_t iteration, uint64_t session_id, const JobBuildOptions& options);

  // The iteration's job ids, by camera: every swept camera with a neighbour. Whether a camera sees
  // a face is known only when its job is built.
  const std::vector<uint64_t>& job_ids() const { return job_ids_; }
  // The jobs of `ids` (ids of this source), built in parallel, each with the bounds its result
  // must fit (from the visible mesh at hand, not unpacked again): std::nullopt for a camera that
  // sees no face of the mesh (it has nothing to sweep). Throws InputError if a job would exceed
  // limits.max_message_bytes (naming the camera and the option to raise). Safe to call from
  // several threads at once (the coordinator builds ahead on one while it sends from another).
  // `threads`: 0 for one per core.
  std::vector<std::optional<BuiltJob>> Build(const std::vector<uint64_t>& ids, int threads = 0);
  // Every job, in id order, without the cameras that see no face (tests, tools).
  std::vector<wire::Job> BuildAll();

  JobBuildStats stats() const;

 private:
  std::optional<BuiltJob> BuildOne(int camera, std::string* skipped) const;

  const Scene& scene_;
  const std::vector<std::vector<int>>& neighbours_;
  std::shared_ptr<const Mesh> mesh_;
  const ImageCatalog& images_;
  uint32_t iteration_;
  uint64_t session_id_;
  JobBuildOptions options_;
  VisibleMeshIndex index_;
  std::vector<uint64_t> job_ids_;
  mutable std::mutex stats_mutex_;  // guards counted_ and stats_
  std::vector<bool> counted_;       // by camera: its job is in stats_ already
  JobBuildStats stats_;
};

}  // namespace ms
