// A camera pair's gradient on the wire (proto/manisweep.proto PairGradient): the refinement
// jobs that workers compute (docs/design/refine.md "Distributed"). Only the vertices the pair
// touches travel; summing the unpacked gradients in pair order gives the bits the local sum gives.
#pragma once

#include <cstddef>
#include <string>

#include "proto/manisweep.pb.h"
#include "refine/photometric_gradient.h"

namespace ms {

void PairGradientToWire(const PairGradient& gradient, wire::PairGradient* out);

// The gradient over `num_vertices` vertices, or "" in `problem` replaced by why the message
// does not fit (sizes, vertex ids not ascending or out of range, non-finite or negative values):
// a result from a buggy or hostile worker is refused, never summed.
PairGradient PairGradientFromWire(const wire::PairGradient& in, size_t num_vertices,
                                  std::string* problem);

}  // namespace ms
