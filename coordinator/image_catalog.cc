#include "coordinator/image_catalog.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
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

ImageCatalog ImageCatalog::WithoutImages(const Scene& scene) {
  ImageCatalog catalog;
  catalog.views_.resize(scene.views.size());
  return catalog;
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

}  // namespace ms
