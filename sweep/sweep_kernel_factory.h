// Choosing a sweep kernel by name, for the `sweep` command and the worker process.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "base/options.h"
#include "sweep/glsl_sweep.h"
#include "sweep/sweep_kernel.h"

namespace ms {

// "glsl": the GLSL kernel (sweep/glsl_sweep.h) on its own GL context, current on the calling
// thread; throws InternalError if no GL 4.3 context can be created or its shaders do not
// compile. "cpu": the fast CPU kernel (sweep/cpu_sweep.h). "reference": the exact C++ reference
// (sweep/reference_sweep.h). "auto": the fastest the machine has: glsl on a GPU, cpu where GL is
// a software rasteriser (llvmpipe) or unavailable. Anything else throws InputError. `why`, if
// given, receives the reason for the choice (for logs and `manisweep info`).
std::unique_ptr<SweepKernel> MakeSweepKernel(const std::string& name,
                                             const GlslSweepKernelOptions& glsl = {},
                                             std::string* why = nullptr);

// The names MakeSweepKernel accepts, "auto" first: "auto", "glsl", "cpu", "reference".
std::vector<std::string> SweepKernelNames();

// --kernel, declared once for every command that sweeps.
struct SweepKernelChoice {
  static constexpr const char* kOptionGroup = "";
#define MS_OPTION_LIST "sweep/sweep_kernel_choice_def.h"
#include "base/option_group_members.h"
  // Throws InputError naming --kernel unless it is one of SweepKernelNames() (or "replay" where
  // `replay_too`: the worker's recorded-run kernel).
  void Check(bool replay_too = false) const;
};

}  // namespace ms
