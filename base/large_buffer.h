// Large per-pixel buffers backed by transparent huge pages where the kernel offers them.
//
// A full-size sweep job touches its per-pixel buffers fresh; with 4 KiB pages that is a page
// fault per 4 KiB, seconds of system time per job on a virtual machine (docs/design/sweep.md).
// Aligned to 2 MiB and advised MADV_HUGEPAGE (the kernel's default THP mode on Debian is
// "madvise"), the same buffers take 512 times fewer faults; freed ones are kept for the next
// allocation of the same size (large_buffer.cc). Small allocations go to the usual allocator,
// aligned to a cache line (the NCC's streaming stores need 64 bytes); contents and results are
// the same either way.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace ms {

namespace large_buffer {
// Allocations from this size up are huge-page aligned and advised; smaller ones are aligned to
// kCacheLine.
constexpr size_t kMinHugeBytes = size_t{4} << 20;
constexpr size_t kCacheLine = 64;
void* Allocate(size_t bytes);
void Free(void* p, size_t bytes);
// Freed blocks kept for reuse, and giving them back to the system (base/memory.h's
// ReleaseFreeMemory does), after which the cache's cap starts again from what is in use.
size_t CachedBytes();
void ReleaseCache();
}  // namespace large_buffer

template <class T>
struct LargeBufferAllocator {
  using value_type = T;
  LargeBufferAllocator() = default;
  template <class U>
  LargeBufferAllocator(const LargeBufferAllocator<U>& /*other*/) {}  // NOLINT: allocator rebind
  T* allocate(size_t n) {
    if (n > static_cast<size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(large_buffer::Allocate(n * sizeof(T)));
  }
  void deallocate(T* p, size_t n) { large_buffer::Free(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const LargeBufferAllocator<U>& /*other*/) const {
    return true;
  }
  template <class U>
  bool operator!=(const LargeBufferAllocator<U>& /*other*/) const {
    return false;
  }
};

// An image-sized array: a std::vector whose large allocations use huge pages.
template <class T>
using LargeBuffer = std::vector<T, LargeBufferAllocator<T>>;

}  // namespace ms
