// Every `manisweep <command>` registers itself here. Each Register* function adds one
// subcommand to the CLI, with its options documented and defaulted, and a callback that runs
// it. Callbacks throw InputError for bad input; main() turns that into one line and exit 2.
#pragma once

#include <CLI/CLI.hpp>

namespace ms::app {

void RegisterInfoCommand(CLI::App& app);
void RegisterCheckMeshCommand(CLI::App& app);
void RegisterSweepCommand(CLI::App& app);
void RegisterSynthCommand(CLI::App& app);
void RegisterEvaluateCommand(CLI::App& app);
void RegisterConvertCommand(CLI::App& app);
void RegisterColmapTriangulateCommand(CLI::App& app);

}  // namespace ms::app
