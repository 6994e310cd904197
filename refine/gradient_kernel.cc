#include "refine/gradient_kernel.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "base/error.h"
#include "gl/context.h"
#include "refine/glsl_gradient.h"

namespace ms {
namespace {

// The CPU kernels: free functions, safe on any number of threads.
class CpuKernel : public PairGradientKernel {
 public:
  using Function = PairGradient (*)(const Mesh&, const RefineView&, const RefineView&,
                                    const RefineOptions&);
  CpuKernel(Function function, std::string name) : function_(function), name_(std::move(name)) {}
  PairGradient Compute(const Mesh& mesh, const RefineView& reference, const RefineView& neighbour,
                       const RefineOptions& options) override {
    return function_(mesh, reference, neighbour, options);
  }
  std::string Name() const override { return name_; }
  bool ThreadSafe() const override { return true; }

 private:
  Function function_;
  std::string name_;
};

std::unique_ptr<PairGradientKernel> FastCpuKernel() {
  return std::make_unique<CpuKernel>(ComputePairGradientFast, "refine-fast-cpu");
}

class GlslKernel : public PairGradientKernel {
 public:
  explicit GlslKernel(std::unique_ptr<GlslPairGradient> glsl) : glsl_(std::move(glsl)) {}
  PairGradient Compute(const Mesh& mesh, const RefineView& reference, const RefineView& neighbour,
                       const RefineOptions& options) override {
    return glsl_->Compute(mesh, reference, neighbour, options);
  }
  std::string Name() const override { return "refine-glsl"; }
  bool ThreadSafe() const override { return false; }

 private:
  std::unique_ptr<GlslPairGradient> glsl_;
};

}  // namespace

std::vector<std::string> PairGradientKernelNames() { return {"auto", "glsl", "cpu", "reference"}; }

std::unique_ptr<PairGradientKernel> MakePairGradientKernel(const std::string& name,
                                                           std::string* why) {
  const auto because = [&](std::string reason) {
    if (why != nullptr) *why = std::move(reason);
  };
  if (name == "cpu") return because("asked for"), FastCpuKernel();
  if (name == "reference")
    return because("asked for"),
           std::make_unique<CpuKernel>(ComputePairGradientReference, "refine-reference");
  if (name == "glsl") {
    return because("asked for"), std::make_unique<GlslKernel>(std::make_unique<GlslPairGradient>());
  }
  if (name == "auto") {
    std::unique_ptr<gl::GlContext> context;
    try {
      context = std::make_unique<gl::GlContext>();
    } catch (const InternalError& e) {
      because(fmt::format("no usable OpenGL 4.3 context ({})", e.what()));
      return FastCpuKernel();
    }
    const gl::GlInfo info = context->info();
    if (info.software) {
      // llvmpipe would run the GLSL passes on the CPU, slower than the CPU kernel.
      context->ReleaseCurrent();
      because(fmt::format("OpenGL renderer '{}' is a software rasteriser", info.renderer));
      return FastCpuKernel();
    }
    because(fmt::format("OpenGL renderer '{}' is a GPU", info.renderer));
    return std::make_unique<GlslKernel>(std::make_unique<GlslPairGradient>(std::move(context)));
  }
  throw InputError(fmt::format("--refine.kernel: '{}' is not one of: {}", name,
                               fmt::join(PairGradientKernelNames(), ", ")));
}

}  // namespace ms
