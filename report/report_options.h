// Options of the run report (report/run_report.h), declared once in report_options_def.h.
#pragma once

#include <string>

#include "base/options.h"

namespace ms {

struct ReportOptions {
  static constexpr const char* kOptionGroup = "report";
#define MS_OPTION_LIST "report/report_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

}  // namespace ms
