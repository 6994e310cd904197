// Job scheduling for the coordinator, without sockets or clocks: who is alive, who works on
// what, which job goes to whom, when a job is given to another worker, and which results
// count. The coordinator feeds it events and the current time; tests feed it a fake clock.
//
// The rules (proto/PROTOCOL.md, after the zguide's Paranoid Pirate pattern):
// - Any message from a peer proves it alive; a peer silent for liveness x heartbeat_interval
//   is dead and forgotten, and its job goes back to the queue.
// - A job handed out carries a lease; when the lease expires without a result the job goes
//   back to the queue (the worker may still deliver: its result counts if it comes first).
// - The first result of a job of the current iteration is accepted; any later one for the same
//   job is a duplicate, one for a job of another iteration is late. Both are ignored.
// - A job handed out max_attempts times without an outcome fails the run (a job that kills
//   every worker must not loop forever).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "base/options.h"

namespace ms {

struct SchedulerOptions {
  static constexpr const char* kOptionGroup = "";
#define MS_OPTION_LIST "coordinator/scheduler_options_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

class JobScheduler {
 public:
  enum class Outcome {
    kAccepted,   // first result of a job of this iteration
    kDuplicate,  // the job is done already
    kLate,       // not a job of this iteration (an earlier iteration, or unknown)
  };

  struct Assignment {
    std::string peer;
    uint64_t job_id = 0;
    int attempt = 0;  // 1 for the first hand-out
  };

  struct Expiry {
    std::vector<std::string> dead_workers;  // names of peers declared dead
    std::vector<uint64_t> requeued;         // jobs back in the queue (dead worker or lease)
  };

  explicit JobScheduler(const SchedulerOptions& options);

  // Starts an iteration with these jobs (ids unique). Workers stay; jobs of the previous
  // iteration are forgotten, so their results arrive late.
  void StartIteration(uint32_t iteration, const std::vector<uint64_t>& job_ids);

  // ---- Events. `peer` is the transport identity, `name` the worker's id (statistics, logs).
  // Any message: the peer is alive; an unknown peer becomes a known idle worker.
  void Touch(const std::string& peer, const std::string& name, double now);
  // READY: the worker (re)starts idle. A job we thought it had goes back to the queue.
  void OnReady(const std::string& peer, const std::string& name, double now);
  // Heartbeat with the worker's view: the job it works on (0: none) and the last it received.
  void OnHeartbeat(const std::string& peer, const std::string& name, uint64_t current_job,
                   uint64_t last_job, double now);
  // A result. The worker is idle afterwards, whatever the outcome.
  Outcome OnResult(const std::string& peer, const std::string& name, uint64_t job_id, double now);
  // The kernel refused the job (it would on every worker): the job is done, without points.
  Outcome OnBadJob(const std::string& peer, const std::string& name, uint64_t job_id, double now);
  // The worker could not do the job (images, memory, a malformed result): the job goes back to
  // the queue; the worker is idle.
  void OnWorkerFailure(const std::string& peer, const std::string& name, uint64_t job_id,
                       double now);
  // The worker did not take `refused`: it is still on `busy_with` (a job of this iteration, or
  // kForeignJob from coordinator/peer_talk.h: another session's, or unknown), e.g. one it got
  // before a reconnection under another peer. The hand-out counts as no attempt; the worker stays
  // out of the idle pool until it reports, and a job of ours it is on is running with it.
  void OnBusy(const std::string& peer, const std::string& name, uint64_t refused,
              uint64_t busy_with, double now);
  // The job handed to `peer` turned out to have nothing to do before it was sent (its camera
  // sees no face): it is done, counted for no worker, and the peer is idle as before.
  void Withdraw(const std::string& peer, uint64_t job_id);
  // Forget a peer now (e.g. it speaks another protocol version); its job is requeued.
  void Remove(const std::string& peer);

  // ---- Time-driven
  Expiry Expire(double now);
  // Peers that are owed a heartbeat now (each is then not due again for an interval).
  std::vector<std::string> DueHeartbeats(double now);
  // Hands pending jobs (in id order) to idle workers (longest idle first).
  std::vector<Assignment> Assign(double now);

  // ---- State
  uint32_t iteration() const { return iteration_; }
  bool IterationComplete() const { return num_done_ == jobs_.size(); }
  // A job that reached max_attempts without an outcome, if any (the run must stop).
  std::optional<uint64_t> exhausted_job() const { return exhausted_; }
  size_t num_jobs() const { return jobs_.size(); }
  size_t num_done() const { return num_done_; }
  size_t num_pending() const;
  // The first `max` pending jobs, in the order Assign hands them out.
  std::vector<uint64_t> PendingJobs(size_t max) const;
  size_t num_running() const;  // handed out, not done, lease not expired
  size_t num_workers() const { return workers_.size(); }
  size_t num_requeued() const { return requeued_; }  // this iteration
  std::vector<std::string> peers() const;
  bool IsKnown(const std::string& peer) const { return workers_.count(peer) > 0; }
  // Accepted outcomes (results and bad jobs) per worker name: this iteration, and in all.
  const std::map<std::string, int64_t>& iteration_job_counts() const { return iteration_counts_; }
  const std::map<std::string, int64_t>& total_job_counts() const { return total_counts_; }
  const SchedulerOptions& options() const { return options_; }

 private:
  enum class State { kPending, kRunning, kDone };
  struct Job {
    State state = State::kPending;
    int attempts = 0;
    double lease_deadline = 0;
    std::set<std::string> holders;  // peers working on it
  };
  struct Worker {
    std::string name;
    double last_seen = 0;
    double next_heartbeat = 0;
    double idle_since = 0;
    uint64_t job = 0;  // 0: idle
  };

  Worker& Register(const std::string& peer, const std::string& name, double now);
  // The worker no longer works on its job; the job is requeued if nobody else has it.
  void Release(Worker& worker, const std::string& peer, double now, bool count_requeue);
  Outcome Finish(const std::string& peer, const std::string& name, uint64_t job_id, double now);

  SchedulerOptions options_;
  uint32_t iteration_ = 0;
  std::map<uint64_t, Job> jobs_;
  std::map<std::string, Worker> workers_;
  size_t num_done_ = 0;
  size_t requeued_ = 0;
  std::optional<uint64_t> exhausted_;
  std::map<std::string, int64_t> iteration_counts_, total_counts_;
};

}  // namespace ms
