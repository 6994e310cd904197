// The worker's images: where to read a job's image files, a disk cache of files fetched from
// the coordinator by content hash, and a memory cache of decoded (gray, undistorted) images.
//
// A file is used from the coordinator's path only if it exists here with the same size and
// content hash (a shared file system, or the same machine); otherwise from the disk cache,
// where fetched files are stored as <directory>/<hash>.img after their hash was verified.
// Thread-safe.
#pragma once

#include <cstdint>
#include <list>
#include <map>
#include <mutex>
#include <string>

#include "scene/camera.h"
#include "sweep/sweep_kernel.h"

namespace ms {

struct ImageCacheOptions {
  // Disk cache of fetched image files; empty = $TMPDIR (or /tmp) /manisweep-image-cache-<uid>.
  std::string directory;
  // Decoded images kept in memory (bytes of float pixels), least recently used dropped first.
  uint64_t memory_bytes = uint64_t{2} << 30;
  void Check() const;  // throws InputError naming the field
};

// An image as a job names it.
struct ImageRef {
  std::string path;  // as the coordinator sees it
  uint64_t hash = 0;
  uint64_t size = 0;
};

class ImageCache {
 public:
  explicit ImageCache(const ImageCacheOptions& options);

  const std::string& directory() const { return directory_; }

  // A local file with exactly this content, or "" if there is none (fetch it). Hashes of
  // local files are remembered by (path, size, modification time).
  std::string Locate(const ImageRef& ref);

  // Verifies `bytes` against ref.hash and ref.size and stores them in the disk cache
  // (atomically). Returns the cached path. Throws InputError if they do not match.
  std::string Store(const ImageRef& ref, const std::string& bytes);

  // The view's image from a local file (see Locate), gray float, undistorted; memoized by
  // content hash and intrinsics. Throws InputError if the file is unreadable or of the wrong
  // size.
  SweepCamera Load(int32_t id, const View& view, uint64_t hash, const std::string& local_path);

  struct Stats {
    int64_t local_hits = 0, disk_hits = 0, misses = 0, stored = 0;
    int64_t decoded = 0, memory_hits = 0;
  };
  Stats stats() const;

 private:
  struct Known {
    uint64_t size = 0;
    int64_t mtime = 0;
    uint64_t hash = 0;
  };
  struct Decoded {
    cv::Mat image;
    std::list<std::string>::iterator lru;
  };
  bool Matches(const std::string& path, const ImageRef& ref);

  ImageCacheOptions options_;
  std::string directory_;
  mutable std::mutex mutex_;
  std::map<std::string, Known> known_;  // local path -> last hash
  std::map<std::string, Decoded> decoded_;
  std::list<std::string> lru_;  // most recent first
  uint64_t decoded_bytes_ = 0;
  Stats stats_;
};

}  // namespace ms
