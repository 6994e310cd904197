// Sweep jobs for one iteration: one per camera, with its neighbours, the part of the current
// mesh it sees, the sweep options, and references to the image files (path, size, content
// hash) that workers read directly or fetch from the coordinator (ImageCatalog).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "mesh/visible_mesh.h"
#include "proto/manisweep.pb.h"
#include "proto/wire.h"
#include "scene/scene.h"
#include "scene/view_selection.h"

namespace ms {

struct ImageRecord {
  std::string path;  // absolute
  uint64_t hash = 0;
  uint64_t size = 0;
  int64_t mtime_ns = 0;  // when hashed; a changed file is refused when serving
};

// The image files of a scene, hashed once, served by content hash.
class ImageCatalog {
 public:
  // Hashes every view's image file. Throws InputError naming the view if it has no image
  // path or the file cannot be read.
  explicit ImageCatalog(const Scene& scene);
  const ImageRecord& view(size_t v) const { return views_.at(v); }
  size_t size() const { return views_.size(); }
  uint64_t total_bytes() const { return total_bytes_; }
  // Answers an ImageRequest: at most min(max_bytes, chunk_limit) bytes from `offset`; found =
  // false with a reason for an unknown hash, an offset past the end, or a file that changed.
  void Serve(uint64_t hash, uint64_t offset, uint64_t max_bytes, uint64_t chunk_limit,
             wire::ImageResponse* response) const;

 private:
  std::vector<ImageRecord> views_;
  std::map<uint64_t, size_t> by_hash_;
  uint64_t total_bytes_ = 0;
};

struct JobBuildOptions {
  VisibleMeshOptions visible;
  wire::SweepOptions sweep;
  double lease_s = 600;
  WireLimits limits;
};

struct IterationJobs {
  std::vector<wire::Job> jobs;       // by camera id
  std::vector<std::string> skipped;  // "camera 3: no neighbour" ...
  int64_t faces = 0;                 // visible faces over all jobs
  uint64_t bytes = 0;                // serialized size of all jobs
};

// One job per camera that has neighbours and sees at least one face. Throws InputError if a
// job would exceed limits.max_message_bytes (naming the camera and the option to raise).
IterationJobs BuildIterationJobs(const Scene& scene,
                                 const std::vector<std::vector<int>>& neighbours, const Mesh& mesh,
                                 const ImageCatalog& images, uint32_t iteration,
                                 uint64_t session_id, const JobBuildOptions& options);

}  // namespace ms
