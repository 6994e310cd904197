// Walks many viewing rays on several threads and counts their crossings (docs/design/manifold.md,
// "Ray tracing on several cores"). The walks only read the triangulation (RayWalker's *With
// walks, a LocalMarks and a WalkScratch per thread) and count with atomic increments
// (CellLabels::CountCrossingConcurrently). A count is a sum of ones, so the counts are exactly
// those of walking the rays one after another, whatever the threads. Internal to manifold/.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "base/parallel_for.h"
#include "manifold/cell_labels.h"
#include "manifold/ray_walker.h"

namespace ms::manifold_detail {

class ParallelWalks {
 public:
  // Rays a thread takes at a time; below two blocks the rays are walked on the calling thread.
  static constexpr size_t kBlock = 256;
  // Rays a caller that streams them (from the ray index) collects before it calls Run.
  static constexpr size_t kChunk = size_t{1} << 18;

  // `walker` and `labels` must outlive this object. threads: 0 for one per core.
  ParallelWalks(RayWalker* walker, CellLabels* labels, int threads = 0)
      : walker_(walker), labels_(labels) {
    set_threads(threads);
  }
  int threads() const { return threads_; }
  void set_threads(int threads) {
    threads_ =
        threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  }

  // For i in [0, n): walk(i, marks, scratch, count) walks ray i with the marks and buffers it
  // is given and calls count(cell, mask) for each crossing to count, returning the cells it
  // stepped through. Returns the sum of those. The camera starts the walks use must be located
  // (RayWalker::LocateStarts).
  template <typename WalkOne>
  int64_t Run(size_t n, WalkOne&& walk) {
    const size_t blocks = (n + kBlock - 1) / kBlock;
    const size_t threads = std::min(blocks, static_cast<size_t>(threads_));
    if (threads <= 1) {
      // One thread: the marks in the cells and plain counting, the cheapest walk.
      StampMarks marks(walker_);
      const auto count = [&](const Cell_handle& c, unsigned mask) {
        labels_->CountCrossing(c, mask);
      };
      int64_t steps = 0;
      for (size_t i = 0; i < n; ++i) steps += walk(i, marks, scratch_, count);
      return steps;
    }
    // Each thread walks the blocks of its own stretch of the rays, then helps the others with
    // theirs: threads far apart in the rays' order (camera by camera) rarely count on the same
    // cells at once. Alternate blocks of one camera's rays had both threads counting on the
    // cells beside it, whose cache lines then pass between the cores (docs/design/manifold.md).
    std::vector<Stretch> stretches(threads);
    for (size_t t = 0; t < threads; ++t) {
      stretches[t].next = blocks * t / threads;
      stretches[t].end = blocks * (t + 1) / threads;
    }
    std::vector<CellLabels::OverflowTally> tallies(threads);
    std::vector<int64_t> steps(threads, 0);
    ParallelFor(
        threads,
        [&](size_t t) {
          LocalMarks marks;
          WalkScratch scratch;
          CellLabels::OverflowTally& tally = tallies[t];
          const auto count = [&](const Cell_handle& c, unsigned mask) {
            labels_->CountCrossingConcurrently(c, mask, &tally);
          };
          for (size_t k = 0; k < threads; ++k) {
            Stretch& stretch = stretches[(t + k) % threads];
            for (size_t b = stretch.next++; b < stretch.end; b = stretch.next++) {
              const size_t end = std::min(n, (b + 1) * kBlock);
              for (size_t i = b * kBlock; i < end; ++i) {
                steps[t] += walk(i, marks, scratch, count);
              }
            }
          }
        },
        static_cast<int>(threads));
    int64_t total = 0;
    for (size_t t = 0; t < threads; ++t) {
      labels_->MergeOverflow(tallies[t]);
      total += steps[t];
    }
    return total;
  }

 private:
  struct alignas(64) Stretch {  // a cache line each: the threads claim blocks side by side
    std::atomic<size_t> next{0};
    size_t end = 0;
  };
  RayWalker* walker_;
  CellLabels* labels_;
  int threads_ = 1;
  WalkScratch scratch_;  // of the walks on the calling thread
};

}  // namespace ms::manifold_detail
