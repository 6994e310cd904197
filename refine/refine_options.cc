#include "refine/refine_options.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "base/error.h"
#include "refine/gradient_kernel.h"

namespace ms {

void RefineOptions::Check() const {
  CheckOptionGroup(*this);
  const std::vector<std::string> kernels = PairGradientKernelNames();
  if (std::find(kernels.begin(), kernels.end(), kernel) == kernels.end()) {
    throw InputError(fmt::format("--refine.kernel: must be one of {}, got '{}'",
                                 fmt::join(kernels, ", "), kernel));
  }
  if (max_edge_px > 0 && min_edge_px >= max_edge_px / 2) {
    throw InputError("--refine.min-edge-px: must be below half of --refine.max-edge-px (" +
                     std::to_string(max_edge_px) + "), or a split edge's halves collapse again");
  }
}

}  // namespace ms
