#include "worker/image_cache.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "base/error.h"
#include "base/file_util.h"
#include "proto/content_hash.h"
#include "sweep/sweep_images.h"

namespace ms {
namespace fs = std::filesystem;

void ImageCacheOptions::Check() const {
  if (memory_bytes > (uint64_t{1} << 40)) {
    throw InputError("memory_bytes: more than 1 TiB of decoded images is surely a mistake");
  }
}

ImageCache::ImageCache(const ImageCacheOptions& options) : options_(options) {
  options_.Check();
  directory_ = options.directory;
  if (directory_.empty()) {
    const char* tmp = std::getenv("TMPDIR");
    directory_ = fmt::format("{}/manisweep-image-cache-{}", tmp && *tmp ? tmp : "/tmp", getuid());
  }
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (!fs::is_directory(directory_)) {
    throw InputError(directory_ + ": cannot create the image cache directory" +
                     (ec ? ": " + ec.message() : std::string()));
  }
}

bool ImageCache::Matches(const std::string& path, const ImageRef& ref) {
  struct stat st;
  if (path.empty() || ::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  if (static_cast<uint64_t>(st.st_size) != ref.size) return false;
  const int64_t mtime = int64_t{st.st_mtim.tv_sec} * 1000000000 + st.st_mtim.tv_nsec;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = known_.find(path);
    if (it != known_.end() && it->second.size == ref.size && it->second.mtime == mtime) {
      return it->second.hash == ref.hash;
    }
  }
  FileHash hash;
  try {
    hash = HashFile(path);
  } catch (const InputError&) {
    return false;  // unreadable here: fetch it
  }
  std::lock_guard<std::mutex> lock(mutex_);
  known_[path] = Known{hash.size, mtime, hash.hash};
  return hash.size == ref.size && hash.hash == ref.hash;
}

std::string ImageCache::Locate(const ImageRef& ref) {
  if (Matches(ref.path, ref)) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.local_hits;
    return ref.path;
  }
  const std::string cached = directory_ + "/" + HashHex(ref.hash) + ".img";
  if (Matches(cached, ref)) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.disk_hits;
    return cached;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.misses;
  return "";
}

std::string ImageCache::Store(const ImageRef& ref, const std::string& bytes) {
  if (bytes.size() != ref.size || HashBytes(bytes) != ref.hash) {
    throw InputError(
        fmt::format("{}: fetched {} bytes with hash {}, expected {} bytes with hash {}", ref.path,
                    bytes.size(), HashHex(HashBytes(bytes)), ref.size, HashHex(ref.hash)));
  }
  const std::string cached = directory_ + "/" + HashHex(ref.hash) + ".img";
  WriteFileAtomically(cached, [&](std::ostream& out) { out.write(bytes.data(), bytes.size()); });
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.stored;
  return cached;
}

SweepCamera ImageCache::Load(int32_t id, const View& view, uint64_t hash,
                             const std::string& local_path) {
  const Intrinsics& k = view.intrinsics;
  // Undistortion depends on the intrinsics, so they are part of the key.
  const std::string key =
      fmt::format("{:016x} {} {} {} {} {} {} {} {} {} {} {}", hash, k.width, k.height, k.fx, k.fy,
                  k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3);
  SweepCamera camera;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = decoded_.find(key);
    if (it != decoded_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      ++stats_.memory_hits;
      camera.id = id;
      camera.view = view;
      camera.view.intrinsics.k1 = camera.view.intrinsics.k2 = camera.view.intrinsics.p1 =
          camera.view.intrinsics.p2 = camera.view.intrinsics.k3 = 0;
      camera.image = it->second.image;  // shared, never written by the kernels
      return camera;
    }
  }
  View local = view;
  local.image_path = local_path;
  camera = LoadSweepCamera(id, local);
  camera.view.image_path = view.image_path;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.decoded;
  const uint64_t bytes = camera.image.total() * camera.image.elemSize();
  if (bytes <= options_.memory_bytes && !decoded_.count(key)) {
    lru_.push_front(key);
    decoded_[key] = Decoded{camera.image, lru_.begin()};
    decoded_bytes_ += bytes;
    while (decoded_bytes_ > options_.memory_bytes && !lru_.empty()) {
      auto victim = decoded_.find(lru_.back());
      decoded_bytes_ -= victim->second.image.total() * victim->second.image.elemSize();
      decoded_.erase(victim);
      lru_.pop_back();
    }
  }
  return camera;
}

ImageCache::Stats ImageCache::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace ms
