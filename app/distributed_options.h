// The option groups of a coordinator run, registered the same way for `manisweep coordinator`
// and `manisweep reconstruct`: one registration, so the commands, config files and docs agree.
#pragma once

#include <CLI/CLI.hpp>

#include "coordinator/coordinator.h"
#include "report/run_report.h"

namespace ms::app {

// Every option of CoordinatorOptions except --input and --output (whose form differs by
// command): the run's own (--resume, --max-iterations, ...), --manifold.*, --neighbours.*,
// --visible.*, --sweep.* and the scheduler's (--lease, --heartbeat-interval, ...).
void AddRunOptions(CLI::App* command, CoordinatorOptions* options);

// --report / --no-report and --report.*: the run report written at the end of the run.
void AddRunReportOptions(CLI::App* command, RunReportRequest* request);

}  // namespace ms::app
