#include "sweep/sweep_kernel_factory.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "base/error.h"
#include "base/log.h"
#include "sweep/cpu_sweep.h"
#include "sweep/reference_sweep.h"

namespace ms {

std::vector<std::string> SweepKernelNames() { return {"auto", "glsl", "cpu", "reference"}; }

void SweepKernelChoice::Check(bool replay_too) const {
  const std::vector<std::string> names = SweepKernelNames();
  if (std::find(names.begin(), names.end(), kernel) != names.end()) return;
  if (replay_too && kernel == "replay") return;
  throw InputError(fmt::format("--kernel: '{}' is not one of: {}{}", kernel, fmt::join(names, ", "),
                               replay_too ? ", replay" : ""));
}

std::unique_ptr<SweepKernel> MakeSweepKernel(const std::string& name,
                                             const GlslSweepKernelOptions& glsl, std::string* why) {
  const auto because = [&](std::string reason) {
    if (why != nullptr) *why = std::move(reason);
  };
  if (name == "reference") return because("asked for"), std::make_unique<ReferenceSweepKernel>();
  if (name == "cpu") return because("asked for"), std::make_unique<CpuSweepKernel>();
  if (name == "glsl") return because("asked for"), std::make_unique<GlslSweepKernel>(glsl);
  if (name == "auto") {
    glsl.Check();  // bad options are the caller's error, not a reason to fall back
    std::unique_ptr<GlslSweepKernel> gpu;
    try {
      gpu = std::make_unique<GlslSweepKernel>(glsl);
    } catch (const InternalError& e) {
      because(fmt::format("no usable OpenGL 4.3 context ({})", e.what()));
      return std::make_unique<CpuSweepKernel>();
    }
    const gl::GlInfo& info = gpu->gl_info();
    if (info.software) {
      // llvmpipe runs the GLSL kernel on the CPU at a third of the CPU kernel's rate.
      because(fmt::format("OpenGL renderer '{}' is a software rasteriser", info.renderer));
      return std::make_unique<CpuSweepKernel>();
    }
    because(fmt::format("OpenGL renderer '{}' is a GPU", info.renderer));
    return gpu;
  }
  throw InputError(fmt::format("sweep kernel '{}' is not one of: {}", name,
                               fmt::join(SweepKernelNames(), ", ")));
}

}  // namespace ms
