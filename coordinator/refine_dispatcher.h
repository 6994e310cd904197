// Photometric refinement on the workers (docs/design/refine.md "Distributed"): every refinement
// iteration, one job per camera pair (the pair, the whole mesh, the pyramid level, the refine
// options) goes to the workers of a bound transport, which return the pair's gradient
// (refine/refine_wire.h); the refiner sums them in pair order, so the refined mesh is the same
// bits with 1, 2 or 30 workers, and the same as the single-process `manisweep refine`.
//
// A network loop runs on its own thread for the dispatcher's lifetime, so workers get
// heartbeats and images while the refiner moves vertices; jobs are scheduled with the sweep's
// rules (coordinator/job_scheduler.h: leases, requeue, dead workers, max attempts).
//
//   RefineDispatcher dispatcher(scene, pairs, options, transport, scheduler, limits, stop);
//   hooks.pair_gradients = dispatcher.Source();
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "coordinator/job_scheduler.h"
#include "mesh/mesh.h"
#include "proto/transport.h"
#include "proto/wire_limits.h"
#include "refine/refiner.h"
#include "scene/scene.h"

namespace ms {

struct RefineDispatchStats {
  int64_t rounds = 0;         // gradient evaluations (one per refinement iteration, about)
  int64_t jobs = 0;           // accepted results
  int64_t requeued = 0;       // jobs handed out again (lease, dead or failing worker)
  int64_t bytes_out = 0;      // serialized jobs sent
  int64_t bytes_in = 0;       // serialized gradients accepted
  double seconds = 0;         // first job out -> last result in, over all rounds
  double worker_seconds = 0;  // the workers' gradient time, summed
};

class RefineDispatcher {
 public:
  // Hashes the scene's images (workers fetch them by hash) and starts the loop on `transport`,
  // bound already and not owned. `stop_requested` is polled by the loop (every few ms): when
  // it says true, the round in progress is abandoned and Compute returns false.
  RefineDispatcher(const Scene& scene, std::vector<std::pair<int, int>> pairs,
                   const RefineOptions& options, ServerTransport* transport,
                   const SchedulerOptions& scheduler, const WireLimits& limits,
                   std::function<bool()> stop_requested);
  // Stops the loop and tells every worker to shut down.
  ~RefineDispatcher();
  RefineDispatcher(const RefineDispatcher&) = delete;
  RefineDispatcher& operator=(const RefineDispatcher&) = delete;

  // The gradients of all pairs for `mesh` at `level`, in pair order (a PairGradientSource).
  // Blocks until every pair's result is in. Returns false if stopped; throws InputError if a
  // job failed on max_attempts workers, a worker refused a job as bad, or a job would exceed
  // the message limit.
  bool Compute(const Mesh& mesh, int level, std::vector<PairGradient>* per_pair);
  PairGradientSource Source() {
    return [this](const Mesh& mesh, int level, std::vector<PairGradient>* out) {
      return Compute(mesh, level, out);
    };
  }

  RefineDispatchStats stats() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ms
