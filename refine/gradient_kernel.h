// Choosing the kernel that computes the pairs' photometric gradients (--refine.kernel), for
// `manisweep refine`, `reconstruct`'s local fallback and the worker process.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "refine/photometric_gradient.h"

namespace ms {

class PairGradientKernel {
 public:
  virtual ~PairGradientKernel() = default;
  virtual PairGradient Compute(const Mesh& mesh, const RefineView& reference,
                               const RefineView& neighbour, const RefineOptions& options) = 0;
  // "refine-fast-cpu", "refine-reference", "refine-glsl": what workers report per job.
  virtual std::string Name() const = 0;
  // Whether several threads may call Compute at once (the CPU kernels; not the GLSL one, which
  // owns one GL context).
  virtual bool ThreadSafe() const = 0;
};

// "cpu": the fast CPU kernel. "reference": the exact double-precision reference. "glsl": the
// GLSL kernel (refine/glsl_gradient.h) on its own GL context; throws InternalError if there is
// none. "auto": glsl on a GPU, cpu where GL is a software rasteriser (llvmpipe) or unavailable.
// Anything else throws InputError. `why`, if given, receives the reason for the choice.
std::unique_ptr<PairGradientKernel> MakePairGradientKernel(const std::string& name,
                                                           std::string* why = nullptr);

// The names MakePairGradientKernel accepts, "auto" first.
std::vector<std::string> PairGradientKernelNames();

}  // namespace ms
