// `manisweep worker`: a sweep worker. Connects to a coordinator, pulls jobs, runs the sweep
// kernel, returns points; reconnects when the coordinator goes away, exits on its Shutdown
// (docs/design/distributed.md, proto/PROTOCOL.md).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <string>

#include "app/commands.h"
#include "app/option_registration.h"
#include "app/process_control.h"
#include "base/error.h"
#include "base/log.h"
#include "coordinator/run_store.h"
#include "proto/zmq_transport.h"
#include "sweep/sweep_kernel_factory.h"
#include "worker/replay_kernel.h"
#include "worker/worker_process.h"

namespace ms::app {
namespace {

struct WorkerCommandOptions {
  WorkerOptions worker;
  ReplayKernelOptions replay;
  std::string connect;
  SweepKernelChoice kernel;
  int threads = 0;
  double image_cache_mb = 2048;
  std::string curve_server_key;
  std::string curve_secret_key;
};

void RunWorker(WorkerCommandOptions& options) {
  options.kernel.Check(true);
  if (!(options.image_cache_mb >= 0)) {
    throw InputError(fmt::format("--image-cache-mb must be >= 0, got {}", options.image_cache_mb));
  }
  if (options.threads < 0) {
    throw InputError(fmt::format("--threads must be >= 0, got {}", options.threads));
  }
  WorkerOptions& w = options.worker;
  w.limits = WireLimitsFromMiB(w.max_message_mb);
  w.cache.memory_bytes = static_cast<uint64_t>(options.image_cache_mb * 1048576);
  w.Check();
  if (options.threads > 0) cv::setNumThreads(options.threads);
  std::string why;
  std::unique_ptr<SweepKernel> kernel;
  if (options.kernel.kernel == "replay") {
    options.replay.Check();
    RunRecord recorded = ReadRunFile(options.replay.run);
    why = fmt::format("{} recorded iterations of {}, {:.2f} s per job",
                      recorded.completed_iterations(), options.replay.run, options.replay.delay_s);
    kernel = std::make_unique<ReplayKernel>(options.replay, std::move(recorded.scene.views),
                                            std::move(recorded.batches));
  } else {
    kernel = MakeSweepKernel(options.kernel.kernel, {}, &why);
  }
  ZmqClientOptions client;
  client.connect = options.connect;
  client.max_message_bytes = w.limits.max_message_bytes;
  client.curve_server_key_file = options.curve_server_key;
  client.curve_secret_key_file = options.curve_secret_key;
  // Key files are checked now; the address at the first connection (Worker::Run).
  if (!client.curve_server_key_file.empty()) {
    RequireCurve("--curve-server-key");
    ReadCurveKeyFile(client.curve_server_key_file, false);
  }
  if (!client.curve_secret_key_file.empty()) ReadCurveKeyFile(client.curve_secret_key_file, true);
  InstallStopSignals();
  const std::string kernel_name = kernel->Name();  // the worker owns the kernel from here
  Worker worker(
      w, [client] { return MakeZmqClient(client); }, std::move(kernel));
  InitLogging("worker " + worker.id());
  spdlog::info("worker {} connecting to {} (kernel {} for --kernel {}: {}; image cache {})",
               worker.id(), options.connect, kernel_name, options.kernel.kernel, why,
               w.cache.directory.empty() ? "default" : w.cache.directory);
  const WorkerSummary summary = worker.Run([] { return StopRequested(); });
  if (summary.exit_reason == "stopped by signal") throw CommandExit(kExitInterrupted);
}

}  // namespace

void RegisterWorkerCommand(CLI::App& app) {
  auto options = std::make_shared<WorkerCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "worker", "Sweep worker of a distributed run: pulls jobs from a coordinator");
  cmd->add_option("-c,--connect", options->connect,
                  "the coordinator's address, e.g. tcp://node01:5555")
      ->required();
  AddOptionGroup(cmd, &options->kernel);
  cmd->add_option("--threads", options->threads, "threads for the kernel (0 = all cores)")
      ->capture_default_str();
  cmd->add_option("--cache-dir", options->worker.cache.directory,
                  "where images fetched from the coordinator are cached (default "
                  "$TMPDIR/manisweep-image-cache-UID)");
  cmd->add_option("--image-cache-mb", options->image_cache_mb,
                  "decoded images kept in memory (MiB)")
      ->capture_default_str();
  cmd->add_option("--curve-server-key", options->curve_server_key,
                  "CURVE: the coordinator's public key file (NAME.key)");
  cmd->add_option("--curve-secret-key", options->curve_secret_key,
                  "CURVE: this worker's key pair (NAME.key_secret); its NAME.key must be in the "
                  "coordinator's --curve-public-keys");
  AddOptionGroup(cmd, &options->worker);
  AddOptionGroup(cmd, &options->replay);
  cmd->callback([options] { RunWorker(*options); });
}

}  // namespace ms::app
