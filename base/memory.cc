#include "base/memory.h"

#include <fmt/format.h>
#include <malloc.h>

#include <algorithm>
#include <fstream>
#include <string>

#include "base/large_buffer.h"

namespace ms {
namespace {

int64_t StatusBytes(const char* field) {
  std::ifstream status("/proc/self/status");
  const std::string prefix = field;
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(prefix, 0) == 0) return std::stoll(line.substr(prefix.size())) * 1024;
  }
  return 0;
}

}  // namespace

int64_t PeakRssBytes() { return StatusBytes("VmHWM:"); }

int64_t ResidentBytes() { return StatusBytes("VmRSS:"); }

int64_t HeapInUseBytes() {
  const struct mallinfo2 info = mallinfo2();
  return static_cast<int64_t>(info.uordblks + info.hblkhd);
}

int64_t ReleaseFreeMemory() {
  const int64_t before = ResidentBytes();
  large_buffer::ReleaseCache();
  malloc_trim(0);
  return std::max<int64_t>(0, before - ResidentBytes());
}

std::string MemoryReport() {
  constexpr double kMiB = 1024.0 * 1024.0;
  return fmt::format("{:.0f} MiB in use, {:.0f} MiB resident, {:.0f} MiB peak",
                     HeapInUseBytes() / kMiB, ResidentBytes() / kMiB, PeakRssBytes() / kMiB);
}

}  // namespace ms
