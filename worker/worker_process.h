// The sweep worker process (`manisweep worker`): connects to the coordinator, says READY,
// pulls jobs, runs the sweep kernel on a compute thread while the main thread keeps the
// conversation going (heartbeats, image fetches), returns results, reconnects with exponential
// back-off when the coordinator goes silent and gives up after a while, and exits on Shutdown.
// The conversation is proto/PROTOCOL.md.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "base/options.h"
#include "proto/transport.h"
#include "proto/wire.h"
#include "sweep/sweep_kernel.h"
#include "worker/image_cache.h"

namespace ms {

struct WorkerOptions {
  static constexpr const char* kOptionGroup = "";
#define MS_OPTION_LIST "worker/worker_options_def.h"
#include "base/option_group_members.h"
  // Set from --cache-dir, --image-cache-mb and --max-message-mb by the command; not options of
  // the group (ForEachOption does not visit them).
  ImageCacheOptions cache;
  WireLimits limits;
  void Check() const;  // throws InputError naming the flag
};

struct WorkerSummary {
  int64_t jobs = 0;         // results sent
  int64_t failed_jobs = 0;  // errors sent
  int64_t points = 0;
  int64_t reconnects = 0;
  int64_t images_fetched = 0;
  std::string exit_reason;  // "shutdown: <reason>", "stopped by signal"
};

using ClientTransportFactory = std::function<std::unique_ptr<ClientTransport>()>;

class Worker {
 public:
  // `connect` makes a fresh connection (called again on every reconnection).
  Worker(const WorkerOptions& options, ClientTransportFactory connect,
         std::unique_ptr<SweepKernel> kernel);
  ~Worker();
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  // Runs until Shutdown or stop_requested() (polled every few ms). Throws InputError when
  // retrying cannot help: the coordinator refused our key or speaks another protocol version,
  // or no coordinator answered for give_up_after_s.
  WorkerSummary Run(const std::function<bool()>& stop_requested);

  const std::string& id() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ms
