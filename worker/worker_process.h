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

#include "proto/transport.h"
#include "proto/wire.h"
#include "worker/image_cache.h"
#include "sweep/sweep_kernel.h"

namespace ms {

struct WorkerOptions {
  std::string id;  // the worker's name in the coordinator's logs and statistics ("" = host:pid)
  // Heartbeat interval and liveness (the coordinator is presumed gone after liveness x
  // interval without a message). Use the coordinator's values.
  double heartbeat_interval_s = 1.0;
  int liveness = 5;
  // Reconnection back-off: first wait, doubling up to the maximum.
  double reconnect_initial_s = 0.5;
  double reconnect_max_s = 16;
  // Give up (exit with an error) after this long without hearing from a coordinator.
  double give_up_after_s = 300;
  ImageCacheOptions cache;
  WireLimits limits;
  // Debugging and tests: sleep this long before each sweep (to catch a worker mid-job).
  double debug_delay_s = 0;
  void Check() const;  // throws InputError naming the field
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
