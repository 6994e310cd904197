#include "worker/kernel_factory.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <functional>

#include "base/error.h"
#include "worker/reference_sweep.h"

namespace ms {
namespace {

struct KernelEntry {
  const char* name;
  // Empty when the kernel is not part of this build; may throw InputError when the machine
  // cannot run it (no GL context), in which case "auto" moves on to the next entry.
  std::function<std::unique_ptr<SweepKernel>()> make;
  const char* unavailable_reason;
};

// In order of preference for "auto". The GLSL kernel goes first once it exists:
//   {"glsl", [] { return MakeGlslSweepKernel(); }, ""},
const std::vector<KernelEntry>& Kernels() {
  static const std::vector<KernelEntry> kernels = {
      {"glsl", nullptr, "the GLSL kernel is not part of this build yet"},
      {"reference", [] { return std::make_unique<ReferenceSweepKernel>(); }, ""},
  };
  return kernels;
}

}  // namespace

std::vector<std::string> SweepKernelNames() {
  std::vector<std::string> names = {"auto"};
  for (const KernelEntry& entry : Kernels()) names.push_back(entry.name);
  return names;
}

std::unique_ptr<SweepKernel> MakeSweepKernel(const std::string& name) {
  if (name == "auto") {
    std::string reasons;
    for (const KernelEntry& entry : Kernels()) {
      if (!entry.make) {
        reasons += fmt::format("; {}: {}", entry.name, entry.unavailable_reason);
        continue;
      }
      try {
        return entry.make();
      } catch (const InputError& e) {
        reasons += fmt::format("; {}: {}", entry.name, e.what());
      }
    }
    throw InputError("--kernel auto: no kernel can run here" + reasons);
  }
  for (const KernelEntry& entry : Kernels()) {
    if (name != entry.name) continue;
    if (!entry.make) {
      throw InputError(
          fmt::format("--kernel {}: {} (use --kernel reference)", name, entry.unavailable_reason));
    }
    return entry.make();
  }
  throw InputError(fmt::format("--kernel {}: unknown kernel (choose from {})", name,
                               fmt::join(SweepKernelNames(), ", ")));
}

}  // namespace ms
