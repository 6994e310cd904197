#include "base/large_buffer.h"

#include <sys/mman.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <vector>

namespace ms::large_buffer {
namespace {

constexpr size_t kHugePage = size_t{2} << 20;

// Freed large blocks kept for the next allocation of the same size: a worker allocates the same
// buffers job after job, and memory fresh from the kernel is zeroed there first (system time
// that grows with the job's size). The cache never holds more than the most
// the process had in large buffers at once, so it adds nothing to the peak.
struct Cache {
  std::mutex mutex;
  std::vector<std::pair<size_t, void*>> blocks;  // rounded size, block
  size_t cached_bytes = 0, live_bytes = 0, peak_live_bytes = 0;
};

Cache& TheCache() {
  static Cache* cache = new Cache;  // never destroyed: buffers may be freed during exit
  return *cache;
}

size_t Rounded(size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }

}  // namespace

void* Allocate(size_t bytes) {
  if (bytes < kMinHugeBytes) {
    const size_t lines = (std::max<size_t>(bytes, 1) + kCacheLine - 1) / kCacheLine;
    void* p = std::aligned_alloc(kCacheLine, lines * kCacheLine);
    if (p == nullptr) throw std::bad_alloc();
    return p;
  }
  const size_t rounded = Rounded(bytes);
  Cache& cache = TheCache();
  {
    std::lock_guard<std::mutex> lock(cache.mutex);
    cache.live_bytes += rounded;
    cache.peak_live_bytes = std::max(cache.peak_live_bytes, cache.live_bytes);
    for (size_t i = 0; i < cache.blocks.size(); ++i) {
      if (cache.blocks[i].first != rounded) continue;
      void* p = cache.blocks[i].second;
      cache.blocks[i] = cache.blocks.back();
      cache.blocks.pop_back();
      cache.cached_bytes -= rounded;
      return p;
    }
  }
  void* p = std::aligned_alloc(kHugePage, rounded);
  if (p == nullptr) {
    std::lock_guard<std::mutex> lock(cache.mutex);
    cache.live_bytes -= rounded;
    throw std::bad_alloc();
  }
#ifdef MADV_HUGEPAGE
  // Advice only: where the kernel has no THP this fails and the pages stay small.
  madvise(p, rounded, MADV_HUGEPAGE);
#endif
  return p;
}

void Free(void* p, size_t bytes) {
  if (p == nullptr) return;
  if (bytes < kMinHugeBytes) {
    std::free(p);
    return;
  }
  const size_t rounded = Rounded(bytes);
  Cache& cache = TheCache();
  {
    std::lock_guard<std::mutex> lock(cache.mutex);
    cache.live_bytes -= rounded;
    if (cache.cached_bytes + cache.live_bytes + rounded <= cache.peak_live_bytes) {
      cache.blocks.emplace_back(rounded, p);
      cache.cached_bytes += rounded;
      return;
    }
  }
  std::free(p);
}

size_t CachedBytes() {
  std::lock_guard<std::mutex> lock(TheCache().mutex);
  return TheCache().cached_bytes;
}

void ReleaseCache() {
  std::vector<std::pair<size_t, void*>> blocks;
  {
    Cache& cache = TheCache();
    std::lock_guard<std::mutex> lock(cache.mutex);
    blocks.swap(cache.blocks);
    cache.cached_bytes = 0;
    cache.peak_live_bytes = cache.live_bytes;  // the cap starts again from what is in use
  }
  for (const auto& [size, p] : blocks) std::free(p);
}

}  // namespace ms::large_buffer
