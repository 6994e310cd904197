// Choosing a sweep kernel by name, for the `sweep` command and the worker process.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sweep/glsl_sweep.h"
#include "sweep/sweep_kernel.h"

namespace ms {

// "glsl": the GLSL kernel (sweep/glsl_sweep.h) on its own GL context, current on the calling
// thread; throws InternalError if no GL 4.3 context can be created or its shaders do not
// compile. "reference": the C++ reference (sweep/reference_sweep.h). "auto": glsl if that works,
// else the reference with a warning in the log. Anything else throws InputError.
std::unique_ptr<SweepKernel> MakeSweepKernel(const std::string& name,
                                             const GlslSweepKernelOptions& glsl = {});

// The names MakeSweepKernel accepts, "auto" first: "auto", "glsl", "reference".
std::vector<std::string> SweepKernelNames();

}  // namespace ms
