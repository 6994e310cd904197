// How much memory this process has taken, for statistics and benchmarks.
#pragma once

#include <cstdint>

namespace ms {

// Peak resident memory of this process so far (VmHWM of /proc/self/status), in bytes; 0 where
// the kernel does not say.
int64_t PeakRssBytes();

}  // namespace ms
