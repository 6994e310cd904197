#include "sweep/sweep_kernel_factory.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "base/error.h"
#include "base/log.h"
#include "sweep/cpu_sweep.h"
#include "sweep/reference_sweep.h"

namespace ms {

std::vector<std::string> SweepKernelNames() { return {"auto", "glsl", "cpu", "reference"}; }

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
    std::unique_ptr<GlslSweepKernel> gl;
    try {
      gl = std::make_unique<GlslSweepKernel>(glsl);
    } catch (const InternalError& e) {
      because(fmt::format("no usable OpenGL 4.3 context ({}); the exact reference", e.what()));
      spdlog::warn("GLSL sweep kernel unavailable, using the C++ reference (slow): {}", e.what());
      return std::make_unique<ReferenceSweepKernel>();
    }
    const gl::GlInfo& info = gl->gl_info();
    // The CPU kernel is 3x faster than llvmpipe but not yet the default there: its Table 1
    // figures differ from the exact kernels' (docs/sweep.md, "Which kernel auto picks").
    because(info.software ? fmt::format("OpenGL renderer '{}' is a software rasteriser; "
                                        "--kernel cpu is 3x faster (docs/sweep.md)",
                                        info.renderer)
                          : fmt::format("OpenGL renderer '{}' is a GPU", info.renderer));
    return gl;
  }
  throw InputError(fmt::format("sweep kernel '{}' is not one of: {}", name,
                               fmt::join(SweepKernelNames(), ", ")));
}

}  // namespace ms
