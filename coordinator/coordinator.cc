#include "coordinator/coordinator.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <thread>

#include "base/error.h"
#include "base/log.h"
#include "coordinator/insertion_batch.h"
#include "coordinator/peer_talk.h"
#include "coordinator/run_lifecycle.h"
#include "proto/content_hash.h"
#include "proto/wire.h"

namespace ms {
namespace {

double Now() { return MonotonicSeconds(); }

const CoordinatorOptions& Checked(const CoordinatorOptions& options) {
  options.Check();
  return options;
}

}  // namespace

void CoordinatorOptions::Check() const {
  if (output_dir.empty()) throw InputError("--output is required");
  if (input.empty() && !run.resume) throw InputError("--input is required unless --resume");
  if (!extend_run.empty() && input.empty()) throw InputError("--input: the new model is required");
  CheckGroups();
}

void CoordinatorOptions::CheckGroups() const {
  run.Check();
  manifold.Check();
  neighbours.Check();
  visible.Check();
  sweep.Check();
  scheduler.Check();
  extend.Check();
  Limits().Check();
}

std::string OptionsFingerprint(const CoordinatorOptions& o) {
  // The groups that change the result; the run's own options and the scheduler's do not.
  const std::string text = OptionGroupText(o.manifold) + " " + OptionGroupText(o.neighbours) + " " +
                           OptionGroupText(o.visible) + " " + OptionGroupText(o.sweep);
  return HashHex(HashBytes(text));
}

OptionValues CoordinatorOptionValues(const CoordinatorOptions& o) {
  OptionValues values;
  for (OptionValues group :
       {OptionGroupValues(o.run), OptionGroupValues(o.manifold), OptionGroupValues(o.neighbours),
        OptionGroupValues(o.visible), OptionGroupValues(o.sweep), OptionGroupValues(o.scheduler),
        OptionGroupValues(o.extend)}) {
    values.insert(values.end(), group.begin(), group.end());
  }
  return values;
}

class Coordinator::Impl : public WorkerMessageHandler {
 public:
  Impl(const CoordinatorOptions& options, ServerTransport* transport)
      : options_(Checked(options)),
        transport_(transport),
        limits_(options.Limits()),
        scheduler_(options.scheduler),
        stamper_("coordinator"),
        session_(NewSessionId()),
        run_(options_, session_) {}

  ~Impl() { WaitForSteps(); }

  CoordinatorResult Run(const std::function<bool()>& stop_requested) {
    spdlog::info("coordinator listening on {} (session {})", transport_->Endpoint(),
                 HashHex(session_));
    try {
      return Loop(stop_requested);
    } catch (...) {
      WaitForSteps();
      Broadcast("the coordinator stopped with an error");
      throw;
    }
  }

 private:
  enum class Phase { kPreparing, kSweeping, kDone };

  // The step in progress, then an early insertion still running (a step waits for it first),
  // and jobs being built ahead.
  void WaitForSteps() {
    if (step_.valid()) step_.wait();
    if (early_insert_.valid()) early_insert_.wait();
    if (building_ahead_.valid()) building_ahead_.wait();
  }

  // ---- The network loop (calling thread)

  CoordinatorResult Loop(const std::function<bool()>& stop_requested) {
    step_ = std::async(std::launch::async, [this] { return run_.Prepare(); });
    phase_ = Phase::kPreparing;
    bool interrupted = false;
    double next_progress = Now() + options_.run.progress_interval_s;
    while (phase_ != Phase::kDone) {
      if (stop_requested && stop_requested()) {
        interrupted = true;
        break;
      }
      const NetworkTurn turn = TurnNetwork(transport_, &scheduler_, &stamper_,
                                           [this](const PeerMessage& m) { Handle(m); });
      const double now = turn.now;
      for (const std::string& name : turn.expiry.dead_workers) {
        spdlog::warn("worker {} went silent for {:.1f} s: presumed dead", name,
                     options_.scheduler.liveness * options_.scheduler.heartbeat_interval_s);
      }
      for (uint64_t job : turn.expiry.requeued) {
        spdlog::warn("job {} (camera {}) goes back to the queue", JobName(job), JobIdCamera(job));
      }
      if (phase_ == Phase::kPreparing &&
          step_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
        StepOutcome outcome = step_.get();
        if (outcome.stop) {
          phase_ = Phase::kDone;
          break;
        }
        StartIteration(std::move(outcome));
      }
      if (phase_ == Phase::kSweeping) {
        run_.CheckCheckpoint();  // the previous iteration's, written meanwhile
        Dispatch(now);
        if (scheduler_.IterationComplete()) {
          round_.seconds_sweep = Now() - sweep_started_;
          if (building_ahead_.valid()) building_ahead_.wait();  // unused now
          building_ahead_ = {};
          built_ahead_.clear();
          RecordJobStats();
          jobs_.reset();  // and with it this iteration's mesh
          // The step must not read the scheduler or the batch while the loop keeps using them.
          round_.jobs_by_worker = scheduler_.iteration_job_counts();
          round_.jobs_requeued = static_cast<int32_t>(scheduler_.num_requeued());
          phase_ = Phase::kPreparing;
          std::vector<RayPoint> rest = batch_.SortedOf(std::vector<uint64_t>(
              job_order_.begin() + static_cast<std::ptrdiff_t>(early_jobs_), job_order_.end()));
          step_ = std::async(std::launch::async, [this, rest = std::move(rest)]() mutable {
            if (early_insert_.valid()) early_insert_.get();
            return run_.Integrate(std::move(rest), round_);
          });
        } else {
          InsertEarly();
        }
        if (phase_ == Phase::kSweeping && now >= next_progress) {
          LogProgress();
          next_progress = now + options_.run.progress_interval_s;
        }
      }
    }
    CoordinatorResult result;
    if (interrupted) {
      spdlog::warn("interrupted: stopping{}", phase_ == Phase::kPreparing
                                                  ? " after the step in progress"
                                                  : "; the last checkpoint stays valid");
      if (step_.valid()) {
        try {
          step_.get();
        } catch (const std::exception& e) {
          spdlog::warn("the step in progress failed while stopping: {}", e.what());
        }
      }
      if (early_insert_.valid()) {
        try {
          early_insert_.get();
        } catch (const std::exception& e) {
          spdlog::warn("the insertion in progress failed while stopping: {}", e.what());
        }
      }
      Broadcast("interrupted");
      result.status = "interrupted";
      result.stop_reason = "interrupted";
      run_.WriteInterruptedSummary();
    } else {
      if (!options_.keep_workers) Broadcast("the run is complete");
      result = run_.final_result();
    }
    result.iterations = run_.completed_iterations();
    return result;
  }

  void Broadcast(const std::string& reason) {
    for (const std::string& peer : scheduler_.peers()) {
      wire::Envelope envelope = stamper_.New();
      envelope.mutable_shutdown()->set_reason(reason);
      transport_->Send(peer, Serialize(envelope));
    }
  }

  void StartIteration(StepOutcome&& outcome) {
    iteration_ = static_cast<uint32_t>(run_.completed_iterations() + 1);
    jobs_ = std::move(outcome.jobs);
    bounds_.clear();
    batch_ = InsertionBatch();
    round_ = SweepRound();
    const std::vector<uint64_t>& ids = jobs_->job_ids();
    for (const std::string& skipped : jobs_->stats().skipped) {
      spdlog::info("iteration {}: no job for {}", iteration_, skipped);
    }
    scheduler_.StartIteration(iteration_, ids);
    job_order_ = ids;  // by camera, the order of the batch
    early_jobs_ = 0;
    sweep_started_ = Now();
    phase_ = Phase::kSweeping;
    spdlog::info("iteration {}/{}: {} jobs, {} workers", iteration_, options_.run.max_iterations,
                 ids.size(), scheduler_.num_workers());
  }

  // The round's job figures, once every job is done.
  void RecordJobStats() {
    const JobBuildStats stats = jobs_->stats();
    round_.jobs = static_cast<int32_t>(stats.jobs);
    round_.cameras_skipped = static_cast<int32_t>(stats.skipped.size());
    round_.seconds_jobs = stats.seconds;
    round_.job_bytes = static_cast<int64_t>(stats.bytes);
    round_.job_max_bytes = static_cast<int64_t>(stats.max_bytes);
    spdlog::info(
        "iteration {}: {} jobs swept ({} visible faces, {:.1f} MiB, the largest {:.0f} KiB, "
        "built in {:.2f} s while sweeping), {} cameras without a job",
        iteration_, stats.jobs, stats.faces, stats.bytes / 1048576.0, stats.max_bytes / 1024.0,
        stats.seconds, stats.skipped.size());
  }

  // Hands the points of the next jobs in camera order whose results are all in to the
  // manifold, one part at a time, while the other jobs are still out: the batch is inserted in
  // camera order anyway, so this is the same insertion, done during the sweep.
  void InsertEarly() {
    if (early_insert_.valid()) {
      if (early_insert_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
      early_insert_.get();  // rethrows what the part threw
    }
    size_t end = early_jobs_;
    while (end < job_order_.size() && batch_.Has(job_order_[end])) ++end;
    if (end == early_jobs_) return;
    std::vector<RayPoint> part = batch_.SortedOf(
        std::vector<uint64_t>(job_order_.begin() + static_cast<std::ptrdiff_t>(early_jobs_),
                              job_order_.begin() + static_cast<std::ptrdiff_t>(end)));
    early_jobs_ = end;
    early_insert_ = std::async(std::launch::async, [this, part = std::move(part)]() mutable {
      run_.InsertEarly(std::move(part));
    });
  }

  // Sends the jobs the scheduler hands out: built ahead when they could be (BuildAhead), else
  // now (in parallel when there are several, as at the start of an iteration). A camera that
  // turns out to see no face has nothing to sweep: its job is done without points, and its
  // worker takes the next one.
  void Dispatch(double now) {
    CollectBuiltAhead();
    while (true) {
      const std::vector<JobScheduler::Assignment> assigned = scheduler_.Assign(now);
      if (assigned.empty()) break;
      std::vector<std::optional<BuiltJob>> jobs(assigned.size());
      std::vector<uint64_t> missing;
      std::vector<size_t> missing_at;
      for (size_t i = 0; i < assigned.size(); ++i) {
        auto ahead = built_ahead_.find(assigned[i].job_id);
        if (ahead != built_ahead_.end()) {
          jobs[i] = std::move(ahead->second);
          built_ahead_.erase(ahead);
        } else {
          missing.push_back(assigned[i].job_id);
          missing_at.push_back(i);
        }
      }
      if (!missing.empty()) {
        std::vector<std::optional<BuiltJob>> built = jobs_->Build(missing);
        for (size_t k = 0; k < missing.size(); ++k) jobs[missing_at[k]] = std::move(built[k]);
      }
      bool withdrawn = false;
      for (size_t i = 0; i < assigned.size(); ++i) {
        const JobScheduler::Assignment& a = assigned[i];
        if (!jobs[i]) {
          scheduler_.Withdraw(a.peer, a.job_id);
          batch_.AddEmpty(a.job_id);
          withdrawn = true;
          continue;
        }
        bounds_.try_emplace(a.job_id, std::move(jobs[i]->bounds));
        wire::Envelope envelope = stamper_.New();
        *envelope.mutable_job() = std::move(jobs[i]->job);
        transport_->Send(a.peer, Serialize(envelope));
        spdlog::debug("job {} -> {}{}", JobName(a.job_id), PeerTag(a.peer),
                      a.attempt > 1 ? fmt::format(" (attempt {})", a.attempt) : "");
      }
      if (!withdrawn) break;  // else the withdrawn jobs' workers are idle again
    }
    BuildAhead();
    if (scheduler_.exhausted_job()) {
      const uint64_t job = *scheduler_.exhausted_job();
      throw InputError(fmt::format(
          "the job of camera {} was handed out {} times without a result (workers died or "
          "failed on it; last failure: {}); stopping",
          JobIdCamera(job), options_.scheduler.max_attempts,
          last_failure_.count(job) ? last_failure_[job] : "none reported"));
    }
  }

  // Builds the next pending jobs in the background, as many as there are workers, so that a
  // worker's next job is usually ready when its result comes in: the network loop then only
  // sends it. On all cores but one: the insertion of the results runs meanwhile.
  void BuildAhead() {
    if (building_ahead_.valid()) return;
    const size_t want = std::max<size_t>(1, scheduler_.num_workers());
    if (built_ahead_.size() >= want) return;
    std::vector<uint64_t> ids;
    for (uint64_t id : scheduler_.PendingJobs(want + built_ahead_.size())) {
      if (!built_ahead_.count(id) && ids.size() < want - built_ahead_.size()) ids.push_back(id);
    }
    if (ids.empty()) return;
    const int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
    building_ahead_ = std::async(std::launch::async, [source = jobs_.get(), ids, threads] {
      std::vector<std::optional<BuiltJob>> jobs = source->Build(ids, threads);
      std::vector<std::pair<uint64_t, std::optional<BuiltJob>>> out;
      for (size_t i = 0; i < ids.size(); ++i) out.emplace_back(ids[i], std::move(jobs[i]));
      return out;
    });
  }

  // Takes the jobs built ahead if they are ready (rethrows what building them threw).
  void CollectBuiltAhead() {
    if (!building_ahead_.valid() ||
        building_ahead_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
      return;
    }
    for (auto& [id, job] : building_ahead_.get()) built_ahead_.emplace(id, std::move(job));
  }

  void LogProgress() {
    const int64_t found = batch_.num_points();
    spdlog::info("iteration {}: {}/{} jobs done, {} running, {} workers, {} points found, {:.1f} s",
                 iteration_, scheduler_.num_done(), scheduler_.num_jobs(), scheduler_.num_running(),
                 scheduler_.num_workers(), found, Now() - sweep_started_);
  }

  void Handle(const PeerMessage& message) {
    if (unfit_.SentAway(message.peer)) {
      junk_.Warn("sent away", fmt::format("dropped a message from {}, sent away earlier",
                                          PeerTag(message.peer)));
      return;
    }
    RouteWorkerMessage(message, Now(), run_.catalog(),
                       {limits_, transport_, &stamper_, &junk_, &scheduler_, session_}, this);
  }

  void OnReady(const std::string& peer, const std::string& sender, const wire::Ready& ready,
               double now) override {
    const bool known = scheduler_.IsKnown(peer);
    scheduler_.OnReady(peer, sender, now);
    spdlog::info("worker {} {} (kernel {}, pid {} on {}); {} workers", sender,
                 known ? "is ready again" : "joined", ready.kernel(), ready.pid(), ready.hostname(),
                 scheduler_.num_workers());
    NoteKernel(sender, ready.kernel());
  }

  void NoteKernel(const std::string& worker, const std::string& kernel) {
    if (kernel_.empty()) {
      kernel_ = kernel;
    } else if (kernel != kernel_ && warned_kernels_.insert(kernel).second) {
      spdlog::warn(
          "worker {} uses the {} kernel, others {}: the result then depends on which "
          "worker swept which camera",
          worker, kernel, kernel_);
    }
  }

  // Checks a result's points against its job. Returns "" if they are usable.
  std::string ValidatePoints(const wire::Result& result, std::vector<FoundPoint>* points) const {
    auto it = bounds_.find(result.job_id());
    if (it == bounds_.end()) return "";  // late or unknown: the scheduler says so
    return ValidateResultPoints(result, it->second, points);
  }

  void OnResult(const std::string& peer, const std::string& sender, const wire::Result& result,
                double now) override {
    if (result.session_id() != session_) {
      // A result for a coordinator before a restart: only the worker's state matters.
      scheduler_.OnResult(peer, sender, kForeignJob, now);
      spdlog::info("ignored a result of another session from worker {} (job {})", sender,
                   JobName(result.job_id()));
      return;
    }
    std::vector<FoundPoint> points;
    const std::string problem = ValidatePoints(result, &points);
    if (!problem.empty()) {
      junk_.Warn("result", fmt::format("dropped the result of job {} from worker {}: {}",
                                       JobName(result.job_id()), sender, problem));
      last_failure_[result.job_id()] = "malformed result: " + problem;
      scheduler_.OnWorkerFailure(peer, sender, result.job_id(), now);
      unfit_.Note(peer, sender, &scheduler_, transport_, &stamper_);
      return;
    }
    const JobScheduler::Outcome outcome = scheduler_.OnResult(peer, sender, result.job_id(), now);
    if (outcome == JobScheduler::Outcome::kAccepted) {
      spdlog::debug("job {}: {} points from worker {} ({:.2f} s)", JobName(result.job_id()),
                    points.size(), sender, result.sweep_seconds());
      round_.kernel_seconds_by_worker[sender] += result.sweep_seconds();
      round_.points_by_worker[sender] += static_cast<int64_t>(points.size());
      round_.jobs_smoothed += result.stats().smoothing_px() > 0;
      round_.image_noise_max = std::max(round_.image_noise_max, result.stats().image_noise());
      batch_.Add(result.job_id(), std::move(points));
      NoteKernel(sender, result.kernel());
    } else {
      spdlog::info("ignored a {} result of job {} from worker {}",
                   outcome == JobScheduler::Outcome::kDuplicate ? "duplicate" : "late",
                   JobName(result.job_id()), sender);
    }
  }

  void OnError(const std::string& peer, const std::string& sender, const wire::Error& error,
               double now) override {
    const bool ours = error.session_id() == session_ && error.job_id() != 0;
    if (HandleBusyOrForeignError(error, ours, "job " + JobName(error.job_id()), session_, peer,
                                 sender, now, &scheduler_)) {
      return;
    }
    if (error.code() == wire::Error::BAD_JOB) {
      if (scheduler_.OnBadJob(peer, sender, error.job_id(), now) ==
          JobScheduler::Outcome::kAccepted) {
        ++round_.jobs_bad;
        batch_.AddEmpty(error.job_id());  // no points from this camera
        spdlog::warn(
            "camera {}: the kernel refused its job ({}); it gives no points this "
            "iteration",
            JobIdCamera(error.job_id()), error.message());
      }
      return;
    }
    last_failure_[error.job_id()] = fmt::format("worker {}: {}", sender, error.message());
    spdlog::warn("worker {} failed on job {}: {}", sender, JobName(error.job_id()),
                 error.message());
    scheduler_.OnWorkerFailure(peer, sender, error.job_id(), now);
  }

  CoordinatorOptions options_;
  ServerTransport* transport_;
  WireLimits limits_;
  JobScheduler scheduler_;
  EnvelopeStamper stamper_;
  uint64_t session_ = 0;
  JunkLog junk_;
  Phase phase_ = Phase::kPreparing;
  // The steps of the run; one at a time on a background thread (step_), while this loop keeps
  // answering the network. The loop calls run_ only between steps, except run_.catalog() and
  // run_.CheckCheckpoint() (the checkpoint written in the background during the sweep).
  RunLifecycle run_;
  std::future<StepOutcome> step_;

  // The current iteration (the loop writes them while sweeping; the step reads them after).
  uint32_t iteration_ = 0;
  std::unique_ptr<IterationJobSource> jobs_;
  std::future<std::vector<std::pair<uint64_t, std::optional<BuiltJob>>>> building_ahead_;
  std::map<uint64_t, std::optional<BuiltJob>> built_ahead_;  // not handed out yet
  std::map<uint64_t, JobBounds> bounds_;                     // what each job handed out must fit
  InsertionBatch batch_;
  std::vector<uint64_t> job_order_;  // this iteration's jobs, by camera
  size_t early_jobs_ = 0;            // of which handed to InsertEarly
  std::future<void> early_insert_;
  SweepRound round_;
  std::map<uint64_t, std::string> last_failure_;
  double sweep_started_ = 0;
  std::string kernel_;
  std::set<std::string> warned_kernels_;
  // Peers whose results did not fit their jobs, and those sent away for it (their messages are
  // dropped from then on).
  UnfitWorkers unfit_;
};

Coordinator::Coordinator(const CoordinatorOptions& options, ServerTransport* transport)
    : impl_(std::make_unique<Impl>(options, transport)) {}

Coordinator::~Coordinator() = default;

CoordinatorResult Coordinator::Run(const std::function<bool()>& stop_requested) {
  return impl_->Run(stop_requested);
}

}  // namespace ms
