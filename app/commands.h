// Every `manisweep <command>` registers itself here. Each Register* function adds one
// subcommand to the CLI, with its options documented and defaulted, and a callback that runs
// it. Callbacks throw InputError for bad input; main() turns that into one line and exit 2.
#pragma once

#include <CLI/CLI.hpp>
#include <exception>

namespace ms::app {

// Thrown by a command that ends without an error but with a non-zero exit code (e.g.
// kExitInterrupted after Ctrl-C); main() returns the code.
class CommandExit : public std::exception {
 public:
  explicit CommandExit(int code) : code_(code) {}
  int code() const { return code_; }
  const char* what() const noexcept override { return "exit"; }

 private:
  int code_;
};

void RegisterInfoCommand(CLI::App& app);
void RegisterManifoldCommand(CLI::App& app);
void RegisterRenderCommand(CLI::App& app);
void RegisterCheckMeshCommand(CLI::App& app);
void RegisterSweepCommand(CLI::App& app);
void RegisterSynthCommand(CLI::App& app);
void RegisterEvaluateCommand(CLI::App& app);
void RegisterConsistencyCommand(CLI::App& app);
void RegisterConvertCommand(CLI::App& app);
void RegisterReconstructCommand(CLI::App& app);
void RegisterExtendCommand(CLI::App& app);
void RegisterCoordinatorCommand(CLI::App& app);
void RegisterWorkerCommand(CLI::App& app);
void RegisterKeygenCommand(CLI::App& app);
void RegisterColmapTriangulateCommand(CLI::App& app);
void RegisterRefineCommand(CLI::App& app);
void RegisterReportCommand(CLI::App& app);

}  // namespace ms::app
