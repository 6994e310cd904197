#include "sweep/sweep_kernel_factory.h"

#include "base/error.h"
#include "base/log.h"
#include "sweep/reference_sweep.h"

namespace ms {

std::vector<std::string> SweepKernelNames() { return {"auto", "glsl", "reference"}; }

std::unique_ptr<SweepKernel> MakeSweepKernel(const std::string& name,
                                             const GlslSweepKernelOptions& glsl) {
  if (name == "reference") return std::make_unique<ReferenceSweepKernel>();
  if (name == "glsl") return std::make_unique<GlslSweepKernel>(glsl);
  if (name == "auto") {
    glsl.Check();  // bad options are the caller's error, not a reason to fall back
    try {
      return std::make_unique<GlslSweepKernel>(glsl);
    } catch (const InternalError& e) {
      spdlog::warn("GLSL sweep kernel unavailable, using the C++ reference (much slower): {}",
                   e.what());
      return std::make_unique<ReferenceSweepKernel>();
    }
  }
  throw InputError("sweep kernel '" + name + "' is not one of: auto, glsl, reference");
}

}  // namespace ms
