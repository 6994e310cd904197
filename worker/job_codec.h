// Conversions between the wire messages (proto/manisweep.proto) and the sweep kernel's results
// (sweep/sweep_kernel.h). The options travel through the generic codec (proto/options_codec.h).
#pragma once

#include "proto/manisweep.pb.h"
#include "sweep/sweep_kernel.h"

namespace ms {

// Points (in the kernel's order) and statistics into a Result; ids and timings are the
// caller's.
void SweepResultToWire(const SweepResult& result, wire::Result* out);

}  // namespace ms
