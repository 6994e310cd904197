#include "coordinator/refine_dispatcher.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <condition_variable>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "base/error.h"
#include "coordinator/image_catalog.h"
#include "coordinator/peer_talk.h"
#include "proto/options_codec.h"
#include "proto/wire.h"
#include "refine/refine_wire.h"

namespace ms {

class RefineDispatcher::Impl : public WorkerMessageHandler {
 public:
  Impl(const Scene& scene, std::vector<std::pair<int, int>> pairs, const RefineOptions& options,
       ServerTransport* transport, const SchedulerOptions& scheduler, const WireLimits& limits,
       std::function<bool()> stop_requested)
      : scene_(scene),
        pairs_(std::move(pairs)),
        options_(options),
        transport_(transport),
        scheduler_options_(scheduler),
        scheduler_(scheduler),
        limits_(limits),
        stop_requested_(std::move(stop_requested)),
        catalog_(scene),
        stamper_("coordinator"),
        session_(NewSessionId()) {
    loop_ = std::thread([this] { LoopGuarded(); });
  }

  ~Impl() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    loop_.join();
  }

  bool Compute(const Mesh& mesh, int level, std::vector<PairGradient>* per_pair) {
    if (pairs_.empty()) {
      per_pair->clear();
      return true;
    }
    std::vector<wire::Job> jobs = BuildJobs(mesh, level);
    std::unique_lock<std::mutex> lock(mutex_);
    if (!error_.empty()) throw InputError(error_);
    if (stopped_) return false;
    request_ = std::move(jobs);
    request_mesh_ = std::move(round_mesh_);
    done_ = false;
    changed_.wait(lock, [&] { return done_ || stopped_ || !error_.empty(); });
    if (!error_.empty()) throw InputError(error_);
    if (!done_) return false;
    *per_pair = std::move(finished_);
    return true;
  }

  RefineDispatchStats stats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stats_;
  }

 private:
  // ---- The caller's thread

  std::vector<wire::Job> BuildJobs(const Mesh& mesh, int level) {
    const uint32_t round = ++rounds_built_;
    wire::Job common;
    common.set_iteration(round);
    common.set_session_id(session_);
    common.set_lease_seconds(scheduler_options_.lease_s);
    common.mutable_refine()->set_mesh_id(round);
    common.mutable_refine()->set_pyramid_level(level);
    OptionsToWire(options_, common.mutable_refine()->mutable_options());
    std::vector<wire::Job> jobs;
    jobs.reserve(pairs_.size());
    for (size_t i = 0; i < pairs_.size(); ++i) {
      wire::Job& job = jobs.emplace_back(common);
      job.set_job_id(MakeJobId(round, static_cast<uint32_t>(i)));
      SetCamera(pairs_[i].first, job.mutable_camera());
      SetCamera(pairs_[i].second, job.add_neighbours());
    }
    // The mesh travels with a worker's first job of the round only (Dispatch).
    wire::PackedMesh packed;
    PackMesh(mesh, &packed);
    for (const wire::Job& job : jobs) {
      const uint64_t bytes = job.ByteSizeLong() + packed.ByteSizeLong() + 16;
      if (bytes + 1024 > limits_.max_message_bytes) {  // room for the envelope
        throw InputError(fmt::format(
            "a refinement job ({} vertices, {} faces) is {} bytes, over the message limit of {} "
            "bytes: raise --max-message-mb on the coordinator and the workers",
            mesh.NumVertices(), mesh.NumFaces(), bytes, limits_.max_message_bytes));
      }
    }
    round_mesh_ = std::move(packed);
    return jobs;
  }

  void SetCamera(int v, wire::JobCamera* camera) const {
    ViewToWire(v, scene_.views[v], camera);
    const ImageRecord& record = catalog_.view(v);
    wire::ImageRef* ref = camera->mutable_image();
    ref->set_path(record.path);
    ref->set_content_hash(record.hash);
    ref->set_byte_size(record.size);
  }

  // ---- The loop's thread

  void LoopGuarded() {
    try {
      Loop();
    } catch (const std::exception& e) {
      Fail(std::string("refinement's network loop failed: ") + e.what());
    }
    Broadcast("refinement is over");
  }

  void Fail(const std::string& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_.empty()) error_ = message;
    changed_.notify_all();
  }

  void Loop() {
    while (true) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (quit_) return;
      }
      const NetworkTurn turn = TurnNetwork(transport_, &scheduler_, &stamper_,
                                           [this](const PeerMessage& m) { Handle(m); });
      const double now = turn.now;
      for (const std::string& name : turn.expiry.dead_workers) {
        spdlog::warn("worker {} went silent: presumed dead", name);
      }
      for (uint64_t job : turn.expiry.requeued) {
        spdlog::warn("refinement job {} goes back to the queue", PairName(job));
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.requeued;
      }
      if (stop_requested_ && stop_requested_()) {
        std::lock_guard<std::mutex> lock(mutex_);
        stopped_ = true;
        changed_.notify_all();
      }
      StartRoundIfAsked(now);
      if (!active_) continue;
      Dispatch(now);
      if (scheduler_.IterationComplete()) FinishRound(now);
    }
  }

  void StartRoundIfAsked(double now) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (request_.empty() || stopped_) return;
    jobs_.clear();
    std::vector<uint64_t> ids;
    for (wire::Job& job : request_) {
      ids.push_back(job.job_id());
      jobs_.emplace(job.job_id(), std::move(job));
    }
    request_.clear();
    round_ = JobIdIteration(ids.front());
    mesh_of_round_ = std::move(request_mesh_);
    gradients_.assign(pairs_.size(), PairGradient());
    scheduler_.StartIteration(round_, ids);
    round_started_ = now;
    active_ = true;
  }

  void FinishRound(double now) {
    active_ = false;
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = std::move(gradients_);
    done_ = true;
    ++stats_.rounds;
    stats_.seconds += now - round_started_;
    changed_.notify_all();
  }

  void Dispatch(double now) {
    for (const JobScheduler::Assignment& a : scheduler_.Assign(now)) {
      wire::Envelope envelope = stamper_.New();
      *envelope.mutable_job() = jobs_.at(a.job_id);
      if (mesh_sent_[a.peer] != round_) {  // the worker's first job of the round
        *envelope.mutable_job()->mutable_mesh() = mesh_of_round_;
        mesh_sent_[a.peer] = round_;
      }
      const std::string bytes = Serialize(envelope);
      transport_->Send(a.peer, bytes);
      std::lock_guard<std::mutex> lock(mutex_);
      stats_.bytes_out += static_cast<int64_t>(bytes.size());
    }
    if (scheduler_.exhausted_job()) {
      const uint64_t job = *scheduler_.exhausted_job();
      active_ = false;
      Fail(fmt::format(
          "the refinement job of camera pair {} was handed out {} times without a result "
          "(workers died or failed on it; last failure: {})",
          PairName(job), scheduler_options_.max_attempts,
          last_failure_.count(job) ? last_failure_[job] : "none reported"));
    }
  }

  // "(3, 4)": the pair of a job, as users know it.
  std::string PairName(uint64_t job_id) const {
    const uint32_t i = JobIdCamera(job_id);
    if (i >= pairs_.size()) return JobName(job_id);
    return fmt::format("({}, {})", pairs_[i].first, pairs_[i].second);
  }

  bool OfThisRound(uint64_t job_id) const { return active_ && jobs_.count(job_id) > 0; }

  void Handle(const PeerMessage& message) {
    if (unfit_.SentAway(message.peer)) return;
    RouteWorkerMessage(message, MonotonicSeconds(), &catalog_,
                       {limits_, transport_, &stamper_, &junk_, &scheduler_, session_}, this);
  }

  void OnReady(const std::string& peer, const std::string& sender, const wire::Ready&,
               double now) override {
    scheduler_.OnReady(peer, sender, now);
    spdlog::info("worker {} ready for refinement; {} workers", sender, scheduler_.num_workers());
  }

  void OnHeartbeatOfNewcomer(const std::string& sender) override {
    spdlog::info("worker {} joins refinement", sender);
  }

  void OnResult(const std::string& peer, const std::string& sender, const wire::Result& result,
                double now) override {
    if (result.session_id() != session_) {  // e.g. a sweep job finishing late
      scheduler_.OnResult(peer, sender, kForeignJob, now);
      return;
    }
    if (!OfThisRound(result.job_id())) {
      scheduler_.OnResult(peer, sender, result.job_id(), now);  // late: ignored
      return;
    }
    std::string problem;
    PairGradient gradient;
    if (result.points_size() > 0 || !result.has_gradient()) {
      problem = "not a refinement result (points, or no gradient)";
    } else {
      gradient = PairGradientFromWire(result.gradient(), mesh_of_round_.num_vertices(), &problem);
    }
    if (!problem.empty()) {
      junk_.Warn("result", fmt::format("dropped the result of refinement job {} from worker {}: {}",
                                       PairName(result.job_id()), sender, problem));
      last_failure_[result.job_id()] = "malformed result: " + problem;
      scheduler_.OnWorkerFailure(peer, sender, result.job_id(), now);
      unfit_.Note(peer, sender, &scheduler_, transport_, &stamper_);
      return;
    }
    if (scheduler_.OnResult(peer, sender, result.job_id(), now) !=
        JobScheduler::Outcome::kAccepted) {
      return;
    }
    gradients_[JobIdCamera(result.job_id())] = std::move(gradient);
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.jobs;
    stats_.bytes_in += static_cast<int64_t>(result.gradient().ByteSizeLong());
    stats_.worker_seconds += result.sweep_seconds();
  }

  void OnError(const std::string& peer, const std::string& sender, const wire::Error& error,
               double now) override {
    const bool ours = error.session_id() == session_ && OfThisRound(error.job_id());
    if (HandleBusyOrForeignError(error, ours, "refinement job " + PairName(error.job_id()),
                                 session_, peer, sender, now, &scheduler_)) {
      return;
    }
    if (error.code() == wire::Error::NEED_MESH) {  // send it again, with the mesh
      mesh_sent_.erase(peer);
      scheduler_.OnWorkerFailure(peer, sender, error.job_id(), now);
      return;
    }
    if (error.code() == wire::Error::BAD_JOB) {
      // The same job fails on every worker: leaving the pair out would change the result
      // silently, so refinement stops with the reason.
      active_ = false;
      Fail(fmt::format("worker {} refused the refinement job of camera pair {}: {}", sender,
                       PairName(error.job_id()), error.message()));
      return;
    }
    last_failure_[error.job_id()] = fmt::format("worker {}: {}", sender, error.message());
    spdlog::warn("worker {} failed on refinement job {}: {}", sender, PairName(error.job_id()),
                 error.message());
    scheduler_.OnWorkerFailure(peer, sender, error.job_id(), now);
  }

  void Broadcast(const std::string& reason) {
    for (const std::string& peer : scheduler_.peers()) {
      wire::Envelope envelope = stamper_.New();
      envelope.mutable_shutdown()->set_reason(reason);
      transport_->Send(peer, Serialize(envelope));
    }
  }

  const Scene& scene_;
  const std::vector<std::pair<int, int>> pairs_;
  const RefineOptions options_;
  ServerTransport* transport_;
  const SchedulerOptions scheduler_options_;
  JobScheduler scheduler_;  // the loop's
  const WireLimits limits_;
  const std::function<bool()> stop_requested_;
  const ImageCatalog catalog_;  // read-only after construction: both threads use it
  EnvelopeStamper stamper_;     // the loop's
  const uint64_t session_;
  uint32_t rounds_built_ = 0;    // the caller's
  wire::PackedMesh round_mesh_;  // the caller's: the mesh of the jobs just built

  // Between the caller and the loop, under mutex_.
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool quit_ = false;
  bool stopped_ = false;
  std::string error_;
  std::vector<wire::Job> request_;  // a round asked for, not yet started
  wire::PackedMesh request_mesh_;   // its mesh
  bool done_ = false;
  std::vector<PairGradient> finished_;
  RefineDispatchStats stats_;

  // The loop's own.
  std::thread loop_;
  bool active_ = false;
  uint32_t round_ = 0;
  double round_started_ = 0;
  std::map<uint64_t, wire::Job> jobs_;  // without the mesh
  wire::PackedMesh mesh_of_round_;
  std::map<std::string, uint32_t> mesh_sent_;  // peer -> the last round whose mesh it got
  std::vector<PairGradient> gradients_;        // by pair, as results come in
  std::map<uint64_t, std::string> last_failure_;
  UnfitWorkers unfit_;
  JunkLog junk_;
};

RefineDispatcher::RefineDispatcher(const Scene& scene, std::vector<std::pair<int, int>> pairs,
                                   const RefineOptions& options, ServerTransport* transport,
                                   const SchedulerOptions& scheduler, const WireLimits& limits,
                                   std::function<bool()> stop_requested)
    : impl_(std::make_unique<Impl>(scene, std::move(pairs), options, transport, scheduler, limits,
                                   std::move(stop_requested))) {}

RefineDispatcher::~RefineDispatcher() = default;

bool RefineDispatcher::Compute(const Mesh& mesh, int level, std::vector<PairGradient>* per_pair) {
  return impl_->Compute(mesh, level, per_pair);
}

RefineDispatchStats RefineDispatcher::stats() const { return impl_->stats(); }

}  // namespace ms
