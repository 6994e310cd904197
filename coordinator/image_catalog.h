// The image files of a scene as the coordinator serves them to workers without a shared file
// system: hashed once (XXH64 of the bytes), then sent in chunks by content hash
// (ImageRequest/ImageResponse, proto/PROTOCOL.md).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "proto/manisweep.pb.h"
#include "scene/scene.h"

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
  // No image at all (coordinator --no-images): every view's record is empty (hash 0, size 0),
  // which workers take as "no image" (only the replay kernel runs such jobs); nothing is served.
  static ImageCatalog WithoutImages(const Scene& scene);
  const ImageRecord& view(size_t v) const { return views_.at(v); }
  size_t size() const { return views_.size(); }
  uint64_t total_bytes() const { return total_bytes_; }
  // Answers an ImageRequest: at most min(max_bytes, chunk_limit) bytes from `offset`; found =
  // false with a reason for an unknown hash, an offset past the end, or a file that changed.
  void Serve(uint64_t hash, uint64_t offset, uint64_t max_bytes, uint64_t chunk_limit,
             wire::ImageResponse* response) const;

 private:
  ImageCatalog() = default;
  std::vector<ImageRecord> views_;
  std::map<uint64_t, size_t> by_hash_;
  uint64_t total_bytes_ = 0;
};

}  // namespace ms
