#include "coordinator/job_builder.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "proto/content_hash.h"

namespace ms {
namespace fs = std::filesystem;
namespace {

int64_t ModificationTime(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return -1;
  return int64_t{st.st_mtim.tv_sec} * 1000000000 + st.st_mtim.tv_nsec;
}

}  // namespace

ImageCatalog::ImageCatalog(const Scene& scene) {
  std::map<std::string, size_t> hashed;  // views may share a file
  for (size_t v = 0; v < scene.views.size(); ++v) {
    const View& view = scene.views[v];
    if (view.image_path.empty()) {
      throw InputError(
          fmt::format("{}: view {} ('{}') has no image file", scene.source, v, view.name));
    }
    std::error_code ec;
    const std::string path = fs::absolute(view.image_path, ec).lexically_normal().string();
    auto it = hashed.find(path);
    if (it != hashed.end()) {
      views_.push_back(views_[it->second]);
      continue;
    }
    ImageRecord record;
    record.path = path;
    record.mtime_ns = ModificationTime(path);
    FileHash hash;
    try {
      hash = HashFile(path);
    } catch (const InputError& e) {
      throw InputError(fmt::format("view {} ('{}'): {}", v, view.name, e.what()));
    }
    record.hash = hash.hash;
    record.size = hash.size;
    total_bytes_ += hash.size;
    by_hash_.emplace(record.hash, views_.size());
    hashed.emplace(path, views_.size());
    views_.push_back(record);
  }
}

void ImageCatalog::Serve(uint64_t hash, uint64_t offset, uint64_t max_bytes, uint64_t chunk_limit,
                         wire::ImageResponse* response) const {
  response->Clear();
  response->set_content_hash(hash);
  response->set_offset(offset);
  auto it = by_hash_.find(hash);
  if (it == by_hash_.end()) {
    response->set_error("no image of the scene has this hash");
    return;
  }
  const ImageRecord& record = views_[it->second];
  response->set_total_size(record.size);
  if (offset > record.size) {
    response->set_error(fmt::format("offset {} past the end ({} bytes)", offset, record.size));
    return;
  }
  if (ModificationTime(record.path) != record.mtime_ns) {
    response->set_error(record.path + " changed since the coordinator hashed it");
    return;
  }
  const uint64_t n =
      std::min({record.size - offset, std::max<uint64_t>(max_bytes, 1), chunk_limit});
  std::string* data = response->mutable_data();
  data->resize(n);
  std::ifstream in(record.path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  in.read(data->data(), static_cast<std::streamsize>(n));
  if (!in || static_cast<uint64_t>(in.gcount()) != n) {
    response->clear_data();
    response->set_error(record.path + ": read error");
    return;
  }
  response->set_found(true);
}

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
  for (size_t c = 0; c < scene.views.size(); ++c) {
    if (neighbours[c].empty()) {
      result.skipped.push_back(fmt::format("camera {}: no neighbour", c));
      continue;
    }
    const VisibleMesh visible = ExtractVisibleMesh(mesh, scene.views[c], options.visible);
    if (visible.mesh.faces.empty()) {
      result.skipped.push_back(fmt::format("camera {}: sees no face of the mesh", c));
      continue;
    }
    wire::Job job;
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
    *job.mutable_options() = options.sweep;
    job.set_lease_seconds(options.lease_s);
    const uint64_t bytes = job.ByteSizeLong();
    // Leave room for the envelope around the job.
    if (bytes + 1024 > options.limits.max_message_bytes) {
      throw InputError(fmt::format(
          "the job of camera {} ({} visible faces) is {} bytes, over the message limit of {} "
          "bytes: raise --max-message-mb on the coordinator and the workers",
          c, visible.mesh.NumFaces(), bytes, options.limits.max_message_bytes));
    }
    result.faces += static_cast<int64_t>(visible.mesh.NumFaces());
    result.bytes += bytes;
    result.jobs.push_back(std::move(job));
  }
  return result;
}

}  // namespace ms
