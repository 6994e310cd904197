#include "app/distributed_options.h"

#include "app/option_registration.h"

namespace ms::app {

void AddRunOptions(CLI::App* command, CoordinatorOptions* options) {
  AddOptionGroup(command, &options->run);
  AddOptionGroup(command, &options->manifold);
  AddOptionGroup(command, &options->neighbours);
  AddOptionGroup(command, &options->visible);
  AddOptionGroup(command, &options->scheduler);
  AddOptionGroup(command, &options->sweep);
}

void AddRunReportOptions(CLI::App* command, RunReportRequest* request) {
  command->add_flag("--report,!--no-report", request->write,
                    "write report.html, the run report, into the output folder at the end "
                    "(docs/guides/report.md); --no-report skips it");
  AddOptionGroup(command, &request->options);
}

}  // namespace ms::app
