// Walks many viewing rays on several threads and counts their crossings (docs/manifold.md,
// "Ray tracing on several cores"). The walks only read the triangulation (RayWalker's *With
// walks, a LocalMarks and a WalkScratch per thread); the crossings they find are counted on the
// calling thread afterwards, a chunk of rays at a time. A count is a sum of ones, so the counts
// are exactly those of walking the rays one after another, whatever the threads. Internal to
// manifold/.
#pragma once

#include <algorithm>
#include <cstdint>
#include <thread>
#include <vector>

#include "base/parallel_for.h"
#include "manifold/ray_walker.h"

namespace ms::manifold_detail {

class ParallelWalks {
 public:
  // Rays a thread takes at a time, and rays whose crossings are held before they are counted
  // (about 45 crossings a ray, 16 bytes each: 12 MB, freed when Run returns).
  static constexpr size_t kBlock = 256;
  static constexpr size_t kChunk = size_t{1} << 14;

  // threads: 0 for one per core.
  explicit ParallelWalks(int threads = 0) { set_threads(threads); }
  void set_threads(int threads) {
    threads_ = threads > 0 ? threads
                           : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  }
  int threads() const { return threads_; }

  // For i in [0, n): walk(i, marks, scratch, record) walks ray i with the thread's marks and
  // buffers and calls record(cell, mask) for each crossing to count, returning the cells it
  // stepped through; then count(cell, mask) is called for every recorded crossing, on this
  // thread. Returns the sum of walk's results.
  template <typename WalkOne, typename Count>
  int64_t Run(size_t n, WalkOne&& walk, Count&& count) {
    int64_t steps = 0;
    for (size_t first = 0; first < n; first += kChunk) {
      const size_t rays = std::min(kChunk, n - first);
      const size_t blocks = (rays + kBlock - 1) / kBlock;
      if (found_.size() < blocks) found_.resize(blocks);
      block_steps_.assign(blocks, 0);
      ParallelFor(
          blocks,
          [&](size_t b) {
            thread_local LocalMarks marks;
            thread_local WalkScratch scratch;
            std::vector<Crossing>& found = found_[b];
            found.clear();
            const auto record = [&](const Cell_handle& c, unsigned mask) {
              found.push_back({c, mask});
            };
            const size_t end = std::min(rays, (b + 1) * kBlock);
            for (size_t i = b * kBlock; i < end; ++i) {
              block_steps_[b] += walk(first + i, marks, scratch, record);
            }
          },
          threads_);
      for (size_t b = 0; b < blocks; ++b) {
        for (const Crossing& c : found_[b]) count(c.cell, c.mask);
        steps += block_steps_[b];
      }
    }
    std::vector<std::vector<Crossing>>().swap(found_);
    return steps;
  }

 private:
  struct Crossing {
    Cell_handle cell;
    unsigned mask;
  };
  int threads_ = 1;
  std::vector<std::vector<Crossing>> found_;  // per block of the chunk
  std::vector<int64_t> block_steps_;
};

}  // namespace ms::manifold_detail
