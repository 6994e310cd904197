// Options of photometric refinement (docs/design/refine.md). The list is
// refine/refine_options_def.h; base/options.h derives the checks and the command line from it.
#pragma once

#include <string>

#include "base/error.h"
#include "base/options.h"

namespace ms {

struct RefineOptions {
  static constexpr const char* kOptionGroup = "refine";
#define MS_OPTION_LIST "refine/refine_options_def.h"
#include "base/option_group_members.h"
  // Throws InputError naming the flag.
  void Check() const {
    CheckOptionGroup(*this);
    if (kernel != "auto" && kernel != "glsl" && kernel != "cpu" && kernel != "reference") {
      throw InputError("--refine.kernel: must be one of auto, glsl, cpu, reference, got '" +
                       kernel + "'");
    }
    if (max_edge_px > 0 && min_edge_px >= max_edge_px / 2) {
      throw InputError("--refine.min-edge-px: must be below half of --refine.max-edge-px (" +
                       std::to_string(max_edge_px) + "), or a split edge's halves collapse again");
    }
  }
};

}  // namespace ms
