// How much memory this process has taken, for statistics, benchmarks and progress output.
#pragma once

#include <cstdint>
#include <string>

namespace ms {

// Peak resident memory of this process so far (VmHWM of /proc/self/status), in bytes; 0 where
// the kernel does not say.
int64_t PeakRssBytes();
// Resident memory now (VmRSS), in bytes; 0 where the kernel does not say.
int64_t ResidentBytes();
// Bytes malloc has handed out and not had back (glibc's mallinfo2): what the program's own
// structures hold, without the allocator's free lists that RSS also counts.
int64_t HeapInUseBytes();
// Gives the allocator's free memory back to the system (glibc's malloc_trim): after a step that
// freed large structures which nothing will reuse soon, so that resident memory follows what
// the program holds. Returns the bytes of resident memory this released (0 if none or unknown).
int64_t ReleaseFreeMemory();
// "812 MiB in use, 850 MiB resident, 1203 MiB peak": for a log line after a step.
std::string MemoryReport();

}  // namespace ms
