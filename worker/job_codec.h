// Conversions between the wire messages (proto/manisweep.proto) and the sweep kernel's types
// (sweep/sweep_kernel.h). The coordinator never sees the kernel's types: the app converts the
// user's SweepOptions here once, and the worker converts jobs and results.
#pragma once

#include "proto/manisweep.pb.h"
#include "sweep/sweep_kernel.h"

namespace ms {

void SweepOptionsToWire(const SweepOptions& options, wire::SweepOptions* out);
// Field by field; the result still needs Check() (the worker runs it through CheckSweepJob).
SweepOptions SweepOptionsFromWire(const wire::SweepOptions& options);

// Points (in the kernel's order) and statistics into a Result; ids and timings are the
// caller's.
void SweepResultToWire(const SweepResult& result, wire::Result* out);

}  // namespace ms
