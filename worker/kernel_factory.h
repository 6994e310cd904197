// Sweep kernels by name, for `manisweep worker --kernel` (and anything else that picks one).
//
//   reference  the C++ reference (worker/reference_sweep.h): CPU, exact, slow
//   glsl       the GLSL kernel on EGL (NVIDIA or Mesa llvmpipe): not in this build yet
//   auto       the best one this build and machine offer (glsl first, then reference)
//
// Adding a kernel is one line in the table in kernel_factory.cc.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "worker/sweep_kernel.h"

namespace ms {

// Names accepted by MakeSweepKernel, "auto" first.
std::vector<std::string> SweepKernelNames();

// Throws InputError for an unknown name, or a known kernel this build or machine cannot run
// (the message says why and which kernels are available).
std::unique_ptr<SweepKernel> MakeSweepKernel(const std::string& name);

}  // namespace ms
