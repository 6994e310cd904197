// Options of the mesh sweep (paper section 2.2, docs/design/sweep.md), sent with every job. The
// list is sweep/sweep_options_def.h; base/options.h derives the checks, the command line, the
// fingerprint and the wire codec from it.
#pragma once

#include "base/options.h"

namespace ms {

struct SweepOptions {
  static constexpr const char* kOptionGroup = "sweep";
#define MS_OPTION_LIST "sweep/sweep_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

}  // namespace ms
