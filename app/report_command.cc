// `manisweep report RUN_DIR`: the run report, one self-contained HTML page (report/run_report.h).
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/option_registration.h"
#include "report/run_report.h"

namespace ms::app {
namespace {

struct ReportCommandOptions {
  std::string run_dir;
  std::string output;
  ReportOptions report;
};

}  // namespace

void RegisterReportCommand(CLI::App& app) {
  auto options = std::make_shared<ReportCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "report",
      "One self-contained HTML page about a run folder: input and options, per-iteration "
      "charts, the meshes pictured beside the photographs, check-mesh, photo-consistency and "
      "(for synth datasets) accuracy");
  cmd->add_option("run_dir", options->run_dir, "the run's output folder (reconstruct --output)")
      ->required();
  cmd->add_option("-o,--output", options->output,
                  "HTML file to write (default RUN_DIR/report.html)");
  AddOptionGroup(cmd, &options->report);
  cmd->callback([options] { WriteRunReport(options->run_dir, options->report, options->output); });
}

}  // namespace ms::app
