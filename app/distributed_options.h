// Command-line options shared by `manisweep coordinator` and `manisweep reconstruct` (and the
// sweep options, which `manisweep sweep` registers the same way): one registration, so the
// commands, config files and docs agree.
#pragma once

#include <CLI/CLI.hpp>

#include "coordinator/coordinator.h"
#include "sweep/sweep_kernel.h"

namespace ms::app {

// --sweep.* (SweepOptions, sweep/sweep_kernel.h).
void AddSweepOptions(CLI::App* cmd, SweepOptions* sweep);

// Everything of a coordinator run except --input/--output/--bind: --resume,
// --max-iterations, --save-iterations, --manifold.*, --neighbours.*, --visible.*, the
// scheduler (--lease, --heartbeat-interval, --liveness, --max-attempts) and --max-message-mb.
// `sweep` receives --sweep.*; call FinishRunOptions after parsing.
void AddRunOptions(CLI::App* cmd, CoordinatorOptions* run, SweepOptions* sweep,
                   double* max_message_mb);

// Checks the sweep options and copies them (and the message limit) into the run options.
void FinishRunOptions(const SweepOptions& sweep, double max_message_mb, CoordinatorOptions* run);

}  // namespace ms::app
