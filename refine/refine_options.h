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
  void Check() const;  // throws InputError naming the flag
};

}  // namespace ms
