// `manisweep coordinator`: the coordinator process of a distributed run. Binds a ZeroMQ ROUTER,
// builds the initial manifold, hands sweep jobs to the workers that connect, inserts their
// points, checkpoints after every iteration (docs/design/distributed.md, proto/PROTOCOL.md); with
// --refine, the same workers then compute the refinement's gradients (docs/design/refine.md).
#include <filesystem>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/distributed_options.h"
#include "app/option_registration.h"
#include "app/process_control.h"
#include "app/refine_run.h"
#include "base/error.h"
#include "base/log.h"
#include "coordinator/coordinator.h"
#include "proto/zmq_transport.h"

namespace ms::app {
namespace {

struct CoordinatorCommandOptions {
  CoordinatorOptions run;
  std::string bind = "tcp://*:5555";
  std::string curve_secret_key;
  std::string curve_public_keys;
  bool insecure = false;
  bool refine = false;  // refine final.ply into refined.ply on the workers (docs/design/refine.md)
  RefineOptions refine_options;
  RunReportRequest report;  // report.html at the end (docs/guides/report.md)
};

void RunCoordinator(CoordinatorCommandOptions& options) {
  options.run.Check();
  options.report.options.Check();
  if (options.refine && options.run.input.empty()) {
    throw InputError("--refine: needs --input (the scene whose images refinement compares)");
  }
  // Without CURVE any process that reaches the port can hand in points; beyond this machine
  // that takes an explicit choice.
  const bool reachable = !IsLocalOnlyEndpoint(options.bind);
  if (reachable && options.curve_secret_key.empty() && !options.insecure) {
    throw InputError(
        "--bind " + options.bind +
        ": listening beyond this machine without CURVE lets anyone who reaches the "
        "port send results; give --curve-secret-key and --curve-public-keys (keys "
        "from `manisweep keygen`, docs/design/distributed.md), bind to 127.0.0.1, or pass "
        "--insecure to accept that");
  }
  InitLogging("coordinator");
  if (reachable && options.curve_secret_key.empty()) {
    spdlog::warn("--insecure: {} accepts unauthenticated, unencrypted workers from the network",
                 options.bind);
  }
  InstallStopSignals();
  ZmqServerOptions server;
  server.bind = options.bind;
  server.max_message_bytes = options.run.Limits().max_message_bytes;
  server.curve_secret_key_file = options.curve_secret_key;
  server.curve_public_keys_dir = options.curve_public_keys;
  std::unique_ptr<ServerTransport> transport = MakeZmqServer(server);
  options.run.keep_workers = options.refine;
  CoordinatorResult result;
  {
    Coordinator coordinator(options.run, transport.get());
    result = coordinator.Run([] { return StopRequested(); });
  }
  if (result.status == "interrupted") throw CommandExit(kExitInterrupted);
  if (options.refine) {
    RefineWorkers workers{transport.get(), options.run.scheduler, options.run.Limits(),
                          [] { return StopRequested(); }};
    RefineMeshFile(options.run.input, result.final_mesh,
                   (std::filesystem::path(options.run.output_dir) / "refined.ply").string(),
                   options.refine_options, options.run.neighbours, false, options.run.run.resume,
                   &workers);
  }
  WriteRunReportAfterRun(options.run.output_dir, options.report);
}

}  // namespace

void RegisterCoordinatorCommand(CLI::App& app) {
  auto options = std::make_shared<CoordinatorCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "coordinator",
      "Coordinator of a distributed run: owns the manifold, hands sweep jobs to workers");
  cmd->add_option("-i,--input", options->run.input,
                  "scene (any supported format); optional with --resume")
      ->capture_default_str();
  cmd->add_option("-o,--output", options->run.output_dir,
                  "output directory: initial.ply, final.ply, run.h5, summary.json")
      ->required();
  cmd->add_option("--bind", options->bind,
                  "ZeroMQ address to listen on (tcp://*:PORT, tcp://IP:PORT; PORT * = any free); "
                  "beyond loopback it needs CURVE keys or --insecure")
      ->capture_default_str();
  cmd->add_option("--curve-secret-key", options->curve_secret_key,
                  "CURVE: this coordinator's key pair (NAME.key_secret from `manisweep keygen`); "
                  "workers then need its public key");
  cmd->add_option("--curve-public-keys", options->curve_public_keys,
                  "CURVE: directory of the allowed workers' public keys (*.key); others are "
                  "refused");
  cmd->add_flag("--insecure", options->insecure,
                "allow a network-reachable --bind without CURVE (anyone reaching the port can "
                "send results)");
  cmd->add_flag("--refine", options->refine,
                "then refine final.ply photometrically into refined.ply on the same workers, "
                "keeping it a closed 2-manifold (docs/design/refine.md)");
  cmd->add_option("--extend-run", options->run.extend_run,
                  "extend this finished run with the new cameras of --input, as `manisweep "
                  "extend` (docs/design/extend.md)");
  AddRunOptions(cmd, &options->run);
  AddOptionGroup(cmd, &options->run.extend);
  AddOptionGroup(cmd, &options->refine_options);
  AddRunReportOptions(cmd, &options->report);
  cmd->callback([options] { RunCoordinator(*options); });
}

}  // namespace ms::app
