// A parallel loop over independent items, for the coordinator's per-camera work (job building).
#pragma once

#include <cstddef>
#include <functional>

namespace ms {

// Runs body(i) for every i in [0, n) on up to `threads` threads (0: one per core), each taking
// the next unclaimed index. If bodies throw, the exception of the smallest index is rethrown
// once all threads have stopped, so errors are the same as those of a sequential loop.
void ParallelFor(size_t n, const std::function<void(size_t)>& body, int threads = 0);

}  // namespace ms
