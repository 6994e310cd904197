// Sweep jobs for one iteration: one per camera, with its neighbours, the part of the current
// mesh it sees, the sweep options, and references to the image files (path, size, content
// hash) that workers read directly or fetch from the coordinator (image_catalog.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "coordinator/image_catalog.h"
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
};

struct IterationJobs {
  std::vector<wire::Job> jobs;       // by camera id
  std::vector<std::string> skipped;  // "camera 3: no neighbour" ...
  int64_t faces = 0;                 // visible faces over all jobs
  uint64_t bytes = 0;                // serialized size of all jobs
  uint64_t max_bytes = 0;            // of the largest
};

// One job per camera that has neighbours and sees at least one face. Throws InputError if a
// job would exceed limits.max_message_bytes (naming the camera and the option to raise).
IterationJobs BuildIterationJobs(const Scene& scene,
                                 const std::vector<std::vector<int>>& neighbours, const Mesh& mesh,
                                 const ImageCatalog& images, uint32_t iteration,
                                 uint64_t session_id, const JobBuildOptions& options);

}  // namespace ms
