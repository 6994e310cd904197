// Options of the mesh sweep (paper section 2.2, docs/sweep.md), sent with every job. The list is
// sweep/sweep_options_def.h; base/options.h derives the checks, the command line, the
// fingerprint and the wire codec from it.
#pragma once

#include "base/options.h"

namespace ms {

struct SweepOptions {
  static constexpr const char* kOptionGroup = "sweep";
#define MS_OPTION MS_OPTION_FIELD
#include "sweep/sweep_options_def.h"
#undef MS_OPTION

  // visit(value, spec) for every option, in declaration order.
  template <typename Self, typename Visitor>
  static void ForEachOption(Self&& self, Visitor&& visit) {
#define MS_OPTION MS_OPTION_VISIT
#include "sweep/sweep_options_def.h"
#undef MS_OPTION
  }
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

}  // namespace ms
