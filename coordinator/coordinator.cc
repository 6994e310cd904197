#include "coordinator/coordinator.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "base/error.h"
#include "base/log.h"
#include "manifold/delaunay_manifold.h"
#include "coordinator/job_builder.h"
#include "coordinator/run_store.h"
#include "manifold/scene_rays.h"
#include "mesh/mesh_checker.h"
#include "mesh/mesh_io.h"
#include "proto/content_hash.h"
#include "scene/scene_io.h"

namespace ms {
namespace fs = std::filesystem;
namespace {

// A worker busy with a job of another session (a coordinator before a restart).
constexpr uint64_t kForeignJob = std::numeric_limits<uint64_t>::max();

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A point returned by a worker, validated.
struct FoundPoint {
  int32_t camera = 0;
  float pixel_x = 0, pixel_y = 0;
  int32_t offset = 0;
  Eigen::Vector3d position;
  std::vector<int32_t> cameras;
};

// The insertion order: by camera, then pixel (row, column), then anything else that could
// differ, so the batch does not depend on which worker delivered what, or when.
bool InsertionOrder(const FoundPoint& a, const FoundPoint& b) {
  return std::tie(a.camera, a.pixel_y, a.pixel_x, a.offset, a.position.x(), a.position.y(),
                  a.position.z(), a.cameras) < std::tie(b.camera, b.pixel_y, b.pixel_x, b.offset,
                                                        b.position.x(), b.position.y(),
                                                        b.position.z(), b.cameras);
}


// What the background thread hands back to the network loop.
struct StepOutcome {
  bool stop = false;
  IterationJobs jobs;  // the next iteration's, unless stop
  double seconds_jobs = 0;
};

// Transport identities are binary; logs show a short hash.
std::string PeerTag(const std::string& peer) {
  return "peer " + HashHex(HashBytes(peer)).substr(0, 8);
}

// Rate-limited warnings about junk from the network: the first few per kind, then every 1000th.
class JunkLog {
 public:
  void Warn(const std::string& kind, const std::string& line) {
    const int64_t n = ++counts_[kind];
    if (n <= 5 || n % 1000 == 0) {
      spdlog::warn("{}{}", line,
                   n == 5  ? " (further ones of this kind are logged every 1000th)"
                   : n > 5 ? fmt::format(" ({} so far)", n)
                           : "");
    }
  }

 private:
  std::map<std::string, int64_t> counts_;
};

}  // namespace

void CoordinatorOptions::Check() const {
  if (output_dir.empty()) throw InputError("output_dir: required (--output)");
  if (input.empty() && !resume) throw InputError("input: required (--input) unless --resume");
  if (max_iterations < 0 || max_iterations > 1000) {
    throw InputError("max_iterations: must be in [0, 1000], got " + std::to_string(max_iterations));
  }
  if (!(progress_interval_s > 0)) throw InputError("progress_interval_s: must be positive");
  manifold.Check();
  neighbours.Check();
  visible.Check();
  scheduler.Check();
  limits.Check();
}

std::string OptionsFingerprint(const CoordinatorOptions& o) {
  const ManifoldOptions& m = o.manifold;
  const std::string text = fmt::format(
      "manifold {} {} {} {} {} {} {} {} {} {} {} {}; neighbours {} {} {}; visible {} {} {}; "
      "sweep {}",
      m.w1, m.w2, m.free_threshold, m.steiner_margin, m.steiner_grid, m.shrink_neighbourhood,
      m.grow_all_components, static_cast<int>(m.w2_rule), static_cast<int>(m.steiner_graded),
      m.graded_steiner_min_points, m.steiner_clearance, m.steiner_min_spacing,
      o.neighbours.max_angle_deg, o.neighbours.count, o.neighbours.same_center_fraction, o.visible.margin_px, o.visible.near,
      o.visible.keep_back_facing, HashHex(HashBytes(Serialize(o.sweep))));
  return HashHex(HashBytes(text));
}

class Coordinator::Impl {
 public:
  Impl(const CoordinatorOptions& options, ServerTransport* transport)
      : options_(options),
        transport_(transport),
        scheduler_(options.scheduler),
        stamper_("coordinator") {
    options_.Check();
    std::random_device random;
    session_ = (uint64_t{random()} << 32) ^ random() ^ static_cast<uint64_t>(Now() * 1e6);
    if (session_ == 0) session_ = 1;
    job_options_.visible = options_.visible;
    job_options_.sweep = options_.sweep;
    job_options_.lease_s = options_.scheduler.lease_s;
    job_options_.limits = options_.limits;
  }

  ~Impl() {
    if (step_.valid()) step_.wait();
  }

  CoordinatorResult Run(const std::function<bool()>& stop_requested) {
    spdlog::info("coordinator listening on {} (session {})", transport_->Endpoint(),
                 HashHex(session_));
    try {
      return Loop(stop_requested);
    } catch (...) {
      if (step_.valid()) step_.wait();
      Broadcast("the coordinator stopped with an error");
      throw;
    }
  }

 private:
  enum class Phase { kPreparing, kSweeping, kDone };

  // ---- The network loop (calling thread)

  CoordinatorResult Loop(const std::function<bool()>& stop_requested) {
    process_timer_.Restart();
    step_ = std::async(std::launch::async, [this] { return Prepare(); });
    phase_ = Phase::kPreparing;
    bool interrupted = false;
    double next_progress = Now() + options_.progress_interval_s;
    while (phase_ != Phase::kDone) {
      if (stop_requested && stop_requested()) {
        interrupted = true;
        break;
      }
      PeerMessage message;
      if (transport_->Receive(0.02, &message)) {
        Handle(message);
        // Drain what is queued before the periodic work, without starving it.
        for (int i = 0; i < 100 && transport_->Receive(0, &message); ++i) Handle(message);
      }
      const double now = Now();
      const JobScheduler::Expiry expiry = scheduler_.Expire(now);
      for (const std::string& name : expiry.dead_workers) {
        spdlog::warn("worker {} went silent for {:.1f} s: presumed dead", name,
                     options_.scheduler.liveness * options_.scheduler.heartbeat_interval_s);
      }
      for (uint64_t job : expiry.requeued) {
        spdlog::warn("job {} (camera {}) goes back to the queue", JobName(job), JobIdCamera(job));
      }
      for (const std::string& peer : scheduler_.DueHeartbeats(now)) {
        wire::Envelope envelope = stamper_.New();
        envelope.mutable_heartbeat();
        transport_->Send(peer, Serialize(envelope));
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
        Dispatch(now);
        if (scheduler_.IterationComplete()) {
          sweep_seconds_ = Now() - sweep_started_;
          // The step must not read the scheduler while the loop keeps using it.
          iteration_counts_ = scheduler_.iteration_job_counts();
          requeued_ = static_cast<int32_t>(scheduler_.num_requeued());
          phase_ = Phase::kPreparing;
          step_ = std::async(std::launch::async, [this] { return Integrate(); });
        } else if (now >= next_progress) {
          LogProgress();
          next_progress = now + options_.progress_interval_s;
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
      Broadcast("interrupted");
      result.status = "interrupted";
      result.stop_reason = "interrupted";
      RunSummaryInfo info = SummaryInfo("interrupted");
      if (record_loaded_) WriteSummaryJson(record_, info, Path("summary.json"));
    } else {
      Broadcast("the run is complete");
      result = final_;
    }
    result.iterations = record_.completed_iterations();
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
    iteration_ = static_cast<uint32_t>(record_.completed_iterations() + 1);
    jobs_.clear();
    results_.clear();
    kernel_seconds_.clear();
    points_by_worker_.clear();
    bad_jobs_ = 0;
    seconds_jobs_ = outcome.seconds_jobs;
    skipped_ = static_cast<int32_t>(outcome.jobs.skipped.size());
    std::vector<uint64_t> ids;
    for (wire::Job& job : outcome.jobs.jobs) {
      ids.push_back(job.job_id());
      jobs_.emplace(job.job_id(), std::move(job));
    }
    scheduler_.StartIteration(iteration_, ids);
    sweep_started_ = Now();
    phase_ = Phase::kSweeping;
    spdlog::info("iteration {}/{}: {} jobs ({} visible faces, {:.1f} MiB), {} workers", iteration_,
                 options_.max_iterations, ids.size(), outcome.jobs.faces,
                 outcome.jobs.bytes / 1048576.0, scheduler_.num_workers());
  }

  void Dispatch(double now) {
    for (const JobScheduler::Assignment& a : scheduler_.Assign(now)) {
      wire::Envelope envelope = stamper_.New();
      *envelope.mutable_job() = jobs_.at(a.job_id);
      transport_->Send(a.peer, Serialize(envelope));
      spdlog::debug("job {} -> {}{}", JobName(a.job_id), PeerTag(a.peer),
                    a.attempt > 1 ? fmt::format(" (attempt {})", a.attempt) : "");
    }
    if (scheduler_.exhausted_job()) {
      const uint64_t job = *scheduler_.exhausted_job();
      throw InputError(fmt::format(
          "the job of camera {} was handed out {} times without a result (workers died or "
          "failed on it; last failure: {}); stopping",
          JobIdCamera(job), options_.scheduler.max_attempts,
          last_failure_.count(job) ? last_failure_[job] : "none reported"));
    }
  }

  void LogProgress() {
    int64_t found = 0;
    for (const auto& [id, points] : results_) found += static_cast<int64_t>(points.size());
    spdlog::info("iteration {}: {}/{} jobs done, {} running, {} workers, {} points found, {:.1f} s",
                 iteration_, scheduler_.num_done(), scheduler_.num_jobs(), scheduler_.num_running(),
                 scheduler_.num_workers(), found, Now() - sweep_started_);
  }

  void Handle(const PeerMessage& message) {
    const std::string who = PeerTag(message.peer);
    if (message.frames != 1) {
      junk_.Warn("frames", fmt::format("dropped a message of {} frames from {} (expected 1)",
                                       message.frames, who));
      return;
    }
    wire::Envelope envelope;
    std::string problem;
    const DecodeStatus status = DecodeEnvelope(message.payload.data(), message.payload.size(),
                                               options_.limits, &envelope, &problem);
    if (status == DecodeStatus::kWrongVersion) {
      const std::string name = envelope.sender().empty() ? who : envelope.sender();
      junk_.Warn("version", fmt::format("refused worker {}: it speaks {}", name, problem));
      wire::Envelope reply = stamper_.New();
      wire::Error* error = reply.mutable_error();
      error->set_code(wire::Error::VERSION_MISMATCH);
      error->set_message(fmt::format("this coordinator speaks protocol version {}, you sent {}",
                                     kProtocolVersion, envelope.protocol_version()));
      transport_->Send(message.peer, Serialize(reply));
      scheduler_.Remove(message.peer);
      return;
    }
    if (status != DecodeStatus::kOk) {
      junk_.Warn(DecodeStatusName(status), fmt::format("dropped a message from {} ({}): {}", who,
                                                       DecodeStatusName(status), problem));
      return;
    }
    const double now = Now();
    const std::string& sender = envelope.sender();
    switch (envelope.body_case()) {
      case wire::Envelope::kReady: {
        const wire::Ready& ready = envelope.ready();
        const bool known = scheduler_.IsKnown(message.peer);
        scheduler_.OnReady(message.peer, sender, now);
        spdlog::info("worker {} {} (kernel {}, pid {} on {}); {} workers", sender,
                     known ? "is ready again" : "joined", ready.kernel(), ready.pid(),
                     ready.hostname(), scheduler_.num_workers());
        NoteKernel(sender, ready.kernel());
        return;
      }
      case wire::Envelope::kHeartbeat: {
        const wire::Heartbeat& h = envelope.heartbeat();
        const bool ours = h.current_job_id() == 0 || h.session_id() == session_;
        scheduler_.OnHeartbeat(message.peer, sender, ours ? h.current_job_id() : kForeignJob,
                               h.last_job_id(), now);
        return;
      }
      case wire::Envelope::kResult:
        OnResult(message.peer, sender, envelope.result(), now);
        return;
      case wire::Envelope::kError:
        OnError(message.peer, sender, envelope.error(), now);
        return;
      case wire::Envelope::kImageRequest: {
        scheduler_.Touch(message.peer, sender, now);
        const wire::ImageRequest& request = envelope.image_request();
        wire::Envelope reply = stamper_.New();
        if (catalog_ready_) {
          catalog_->Serve(request.content_hash(), request.offset(), request.max_bytes(),
                          options_.limits.image_chunk_bytes, reply.mutable_image_response());
        } else {
          reply.mutable_image_response()->set_content_hash(request.content_hash());
          reply.mutable_image_response()->set_error("the coordinator is still starting");
        }
        if (!reply.image_response().found()) {
          spdlog::warn("worker {} asked for image {}: {}", sender, HashHex(request.content_hash()),
                       reply.image_response().error());
        } else if (request.offset() == 0) {
          spdlog::info("sending image {} ({} bytes) to worker {}", HashHex(request.content_hash()),
                       reply.image_response().total_size(), sender);
        }
        transport_->Send(message.peer, Serialize(reply));
        return;
      }
      default:
        scheduler_.Touch(message.peer, sender, now);
        junk_.Warn("unexpected", fmt::format("dropped an unexpected {} message from {}",
                                             BodyName(envelope), sender));
        return;
    }
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
    auto it = jobs_.find(result.job_id());
    if (it == jobs_.end()) return "";  // late or unknown: the scheduler says so
    const int32_t camera = it->second.camera().id();
    const int32_t num_views = static_cast<int32_t>(record_.scene.views.size());
    for (int i = 0; i < result.points_size(); ++i) {
      const wire::SweepPoint& p = result.points(i);
      FoundPoint f;
      f.camera = camera;
      f.pixel_x = p.pixel_x();
      f.pixel_y = p.pixel_y();
      f.offset = p.offset();
      f.position = Eigen::Vector3d(p.x(), p.y(), p.z());
      if (!f.position.allFinite() || !std::isfinite(f.pixel_x) || !std::isfinite(f.pixel_y)) {
        return fmt::format("point {} is not finite", i);
      }
      if (p.cameras_size() < 1 || p.cameras(0) != camera) {
        return fmt::format("point {} does not list camera {} first", i, camera);
      }
      std::set<int32_t> seen;
      for (int32_t c : p.cameras()) {
        if (c < 0 || c >= num_views || !seen.insert(c).second) {
          return fmt::format("point {} lists camera {} (twice, or not in the scene)", i, c);
        }
        f.cameras.push_back(c);
      }
      points->push_back(std::move(f));
    }
    return "";
  }

  void OnResult(const std::string& peer, const std::string& sender, const wire::Result& result,
                double now) {
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
      return;
    }
    const JobScheduler::Outcome outcome = scheduler_.OnResult(peer, sender, result.job_id(), now);
    if (outcome == JobScheduler::Outcome::kAccepted) {
      spdlog::debug("job {}: {} points from worker {} ({:.2f} s)", JobName(result.job_id()),
                    points.size(), sender, result.sweep_seconds());
      kernel_seconds_[sender] += result.sweep_seconds();
      points_by_worker_[sender] += static_cast<int64_t>(points.size());
      results_[result.job_id()] = std::move(points);
      NoteKernel(sender, result.kernel());
    } else {
      spdlog::info("ignored a {} result of job {} from worker {}",
                   outcome == JobScheduler::Outcome::kDuplicate ? "duplicate" : "late",
                   JobName(result.job_id()), sender);
    }
  }

  void OnError(const std::string& peer, const std::string& sender, const wire::Error& error,
               double now) {
    const bool ours = error.session_id() == session_ && error.job_id() != 0;
    if (!ours) {
      scheduler_.Touch(peer, sender, now);
      if (error.job_id() != 0) scheduler_.OnResult(peer, sender, kForeignJob, now);
      spdlog::warn("worker {} reports: {}", sender, error.message());
      return;
    }
    if (error.code() == wire::Error::BAD_JOB) {
      if (scheduler_.OnBadJob(peer, sender, error.job_id(), now) ==
          JobScheduler::Outcome::kAccepted) {
        ++bad_jobs_;
        results_[error.job_id()];  // no points from this camera
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

  // ---- Background steps (one at a time; the network loop never touches what they use)

  std::string Path(const std::string& name) const {
    return (fs::path(options_.output_dir) / name).string();
  }

  // Build or replay, write the initial mesh, and the first jobs.
  StepOutcome Prepare() {
    fs::create_directories(options_.output_dir);
    const std::string run_file = Path("run.h5");
    const std::string fingerprint = OptionsFingerprint(options_);
    bool resuming = false;
    if (fs::exists(run_file)) {
      if (!options_.resume) {
        throw InputError(options_.output_dir +
                         " holds a run already (run.h5): pass --resume to continue it, or "
                         "choose another --output");
      }
      resuming = true;
    } else if (options_.resume) {
      spdlog::warn("--resume: no {} yet; starting a new run", run_file);
      if (options_.input.empty()) throw InputError("--resume without a run.h5 needs --input");
    }
    resumed_ = resuming;
    Scene input;
    if (!options_.input.empty()) {
      input = ReadScene(options_.input);
      input.Validate();
    }
    if (resuming) {
      record_ = ReadRunFile(run_file);
      if (record_.options_fingerprint != fingerprint) {
        throw InputError(run_file +
                         ": the run was made with other options (manifold, sweep, "
                         "neighbour or visible-mesh options differ); resume with the same ones");
      }
      if (!options_.input.empty() && SceneFingerprint(input) != record_.scene_fingerprint) {
        throw InputError(options_.input + ": not the scene of the run in " + run_file);
      }
      spdlog::info("resuming {}: {} iterations done", run_file, record_.completed_iterations());
    } else {
      record_ = RunRecord();
      record_.scene = std::move(input);
      record_.scene_fingerprint = SceneFingerprint(record_.scene);
      record_.options_fingerprint = fingerprint;
    }
    record_loaded_ = true;
    const Scene& scene = record_.scene;
    spdlog::info("scene: {}", scene.Summary());
    Timer hashing;
    catalog_ = std::make_unique<ImageCatalog>(scene);
    catalog_ready_ = true;
    spdlog::info("hashed {} image files ({:.1f} MiB) in {:.2f} s", catalog_->size(),
                 catalog_->total_bytes() / 1048576.0, hashing.Seconds());
    neighbours_.clear();
    for (size_t c = 0; c < scene.views.size(); ++c) {
      neighbours_.push_back(SelectNeighbours(scene, static_cast<int>(c), options_.neighbours));
    }

    manifold_ =
        std::make_unique<DelaunayManifold>(ManifoldCamerasFromScene(scene), options_.manifold);
    Timer build;
    const BuildStats stats = manifold_->Build(RayPointsFromScene(scene));
    const double build_s = build.Seconds();
    spdlog::info("initial manifold: {} points ({} Steiner), {} cells, {} outside; {:.2f} s",
                 stats.points, stats.steiner_points, stats.cells, stats.outside_cells, build_s);
    if (resuming) {
      for (int i = 0; i < record_.completed_iterations(); ++i) {
        Timer replay;
        const InsertionStats s = manifold_->Insert(record_.batches[i]);
        spdlog::info("replayed iteration {}: {} of {} points inserted, {:.2f} s", i + 1, s.inserted,
                     s.requested, replay.Seconds());
        if (s.inserted != record_.iterations[i + 1].points_inserted) {
          throw InputError(fmt::format(
              "{}: replaying iteration {} inserted {} points where the run inserted {}: the "
              "manifold code differs from the one that made the checkpoint",
              run_file, i + 1, s.inserted, record_.iterations[i + 1].points_inserted));
        }
      }
      Extract();
      if (!fs::exists(Path("initial.ply"))) {
        spdlog::warn("initial.ply is missing; it is not rewritten on resume");
      }
    } else {
      Timer extract;
      Extract();
      if (mesh_.faces.empty()) {
        throw InputError(options_.input + ": the initial manifold is empty: no cell reached the "
                         "free-space threshold (check the points' visibility and "
                         "--manifold.free-threshold)");
      }
      WriteMesh(mesh_, Path("initial.ply"));
      WriteMesh(surface_, Path("initial_surface.ply"));
      IterationStats row;
      row.iteration = 0;
      row.points_found = static_cast<int64_t>(scene.points.size());
      row.points_inserted = stats.points - stats.merged_duplicates;
      row.discarded_duplicate = stats.merged_duplicates;
      row.vertices = static_cast<int64_t>(mesh_.NumVertices());
      row.faces = static_cast<int64_t>(mesh_.NumFaces());
      row.outside_cells = stats.outside_cells;
      row.seconds_insert = build_s;
      row.seconds_extract = extract.Seconds();
      row.seconds_total = build_s + row.seconds_extract;
      record_.iterations.push_back(row);
      Checkpoint();
      spdlog::info("initial mesh: {} vertices, {} faces -> {}", mesh_.NumVertices(),
                   mesh_.NumFaces(), Path("initial.ply"));
    }
    return NextOrStop();
  }

  // After an iteration's sweep: sort, insert, extract, checkpoint, and the next jobs.
  StepOutcome Integrate() {
    std::vector<FoundPoint> found;
    for (auto& [id, points] : results_) {
      for (FoundPoint& p : points) found.push_back(std::move(p));
    }
    std::sort(found.begin(), found.end(), InsertionOrder);
    std::vector<RayPoint> batch;
    batch.reserve(found.size());
    for (FoundPoint& p : found) {
      RayPoint r;
      r.position = p.position;
      r.cameras = std::move(p.cameras);
      batch.push_back(std::move(r));
    }
    Timer insert;
    const InsertionStats s = manifold_->Insert(batch);
    const double insert_s = insert.Seconds();
    Timer extract;
    Extract();
    if (options_.save_iteration_meshes) {
      WriteMesh(mesh_, Path(fmt::format("iteration_{:02d}.ply", iteration_)));
    }
    IterationStats row;
    row.iteration = static_cast<int32_t>(iteration_);
    row.jobs = static_cast<int32_t>(jobs_.size());
    row.jobs_bad = bad_jobs_;
    row.jobs_requeued = requeued_;
    row.cameras_skipped = skipped_;
    row.points_found = static_cast<int64_t>(batch.size());
    row.points_inserted = s.inserted;
    row.discarded_conflict = s.discarded_conflict;
    row.discarded_duplicate = s.discarded_duplicate;
    row.discarded_outside = s.discarded_outside;
    row.vertices = static_cast<int64_t>(mesh_.NumVertices());
    row.faces = static_cast<int64_t>(mesh_.NumFaces());
    row.outside_cells = s.outside_cells;
    row.seconds_jobs = seconds_jobs_;
    row.seconds_sweep = sweep_seconds_;
    row.seconds_insert = insert_s;
    row.seconds_extract = extract.Seconds();
    const auto& counts = iteration_counts_;
    row.workers = static_cast<int32_t>(counts.size());
    for (const auto& [name, jobs] : counts) {
      WorkerIterationStats w;
      w.iteration = row.iteration;
      w.worker = name.substr(0, 255);
      w.jobs = jobs;
      w.points = points_by_worker_.count(name) ? points_by_worker_.at(name) : 0;
      w.seconds_kernel = kernel_seconds_.count(name) ? kernel_seconds_.at(name) : 0;
      row.seconds_kernel += w.seconds_kernel;
      record_.workers.push_back(w);
    }
    row.seconds_total =
        row.seconds_jobs + row.seconds_sweep + row.seconds_insert + row.seconds_extract;
    record_.batches.push_back(std::move(batch));
    record_.iterations.push_back(row);
    Checkpoint();
    const IterationStats& done = record_.iterations.back();
    spdlog::info(
        "iteration {} done: {} points found, {} inserted, {} discarded; mesh {} vertices, {} "
        "faces; jobs {:.2f} s, sweep {:.2f} s, insert {:.2f} s, extract {:.2f} s, checkpoint "
        "{:.2f} s",
        iteration_, done.points_found, done.points_inserted,
        done.discarded_conflict + done.discarded_duplicate + done.discarded_outside, done.vertices,
        done.faces, done.seconds_jobs, done.seconds_sweep, done.seconds_insert,
        done.seconds_extract, done.seconds_checkpoint);
    return NextOrStop();
  }

  // Writes run.h5 and summary.json; the time it took goes into the last row (and reaches the
  // file with the next checkpoint).
  void Checkpoint() {
    Timer timer;
    WriteRunFile(record_, Path("run.h5"));
    record_.iterations.back().seconds_checkpoint = timer.Seconds();
    record_.iterations.back().seconds_total += timer.Seconds();
    WriteSummaryJson(record_, SummaryInfo(record_.stop_reason.empty() ? "running" : "finished"),
                     Path("summary.json"));
  }

  RunSummaryInfo SummaryInfo(const std::string& status) const {
    RunSummaryInfo info;
    info.status = status;
    info.input = options_.input;
    info.seconds = process_timer_.Seconds();
    info.resumed = resumed_;
    if (status == "finished") {
      info.final_mesh = final_.final_mesh;
      info.final_is_closed_manifold = final_.final_is_closed_manifold;
      info.mesh_check = final_check_;
    }
    return info;
  }

  StepOutcome NextOrStop() {
    StepOutcome outcome;
    const int done = record_.completed_iterations();
    std::string reason;
    if (done >= 1 && record_.iterations.back().points_inserted == 0) {
      reason = "converged: no new point was inserted";
    } else if (done >= options_.max_iterations) {
      reason = fmt::format("reached --max-iterations {}", options_.max_iterations);
    } else {
      Timer timer;
      outcome.jobs = BuildIterationJobs(record_.scene, neighbours_, surface_, *catalog_,
                                        static_cast<uint32_t>(done + 1), session_, job_options_);
      outcome.seconds_jobs = timer.Seconds();
      for (const std::string& skipped : outcome.jobs.skipped) {
        spdlog::info("iteration {}: no job for {}", done + 1, skipped);
      }
      if (outcome.jobs.jobs.empty()) reason = "no camera has a job (no neighbours or no face)";
    }
    if (reason.empty()) return outcome;
    Finish(reason);
    outcome.stop = true;
    return outcome;
  }

  void Finish(const std::string& reason) {
    const std::string path = Path("final.ply");
    WriteMesh(mesh_, path);
    WriteMesh(surface_, Path("final_surface.ply"));
    MeshCheckOptions check;
    check.check_self_intersections = false;  // exact but slow on large meshes
    const MeshReport report = CheckMesh(mesh_, check);
    const std::vector<std::string> problems = report.Problems();
    final_check_ = report.is_closed_manifold
                       ? "closed, oriented 2-manifold (self-intersections not checked)"
                       : "not a closed 2-manifold: " + (problems.empty() ? "" : problems[0]);
    final_.status = "finished";
    final_.stop_reason = reason;
    final_.final_mesh = path;
    final_.vertices = static_cast<int64_t>(mesh_.NumVertices());
    final_.faces = static_cast<int64_t>(mesh_.NumFaces());
    final_.final_is_closed_manifold = report.is_closed_manifold;
    record_.stop_reason = reason;
    Checkpoint();
    spdlog::info("finished after {} iterations ({}): {} vertices, {} faces -> {}; {}",
                 record_.completed_iterations(), reason, final_.vertices, final_.faces, path,
                 final_check_);
  }

  CoordinatorOptions options_;
  ServerTransport* transport_;
  JobScheduler scheduler_;
  EnvelopeStamper stamper_;
  uint64_t session_ = 0;
  JobBuildOptions job_options_;
  JunkLog junk_;
  Timer process_timer_;
  Phase phase_ = Phase::kPreparing;
  std::future<StepOutcome> step_;

  // Owned by the background step while it runs; read by the loop only between steps, except
  // catalog_ (immutable once catalog_ready_ is set) and the scene (immutable after Prepare).
  RunRecord record_;
  std::atomic<bool> record_loaded_{false};
  bool resumed_ = false;
  std::unique_ptr<ImageCatalog> catalog_;
  std::atomic<bool> catalog_ready_{false};
  std::vector<std::vector<int>> neighbours_;
  std::unique_ptr<DelaunayManifold> manifold_;
  // The closed manifold, and the surface proper (without the Steiner faces that close it):
  // what the sweep jobs are built from (docs/manifold.md).
  void Extract() {
    SurfaceInfo info;
    mesh_ = manifold_->ExtractSurface(&info);
    surface_ = SurfaceWithoutSteinerFaces(mesh_, info);
  }
  Mesh mesh_;
  Mesh surface_;
  CoordinatorResult final_;
  std::string final_check_;

  // The current iteration (the loop writes them while sweeping; the step reads them after).
  uint32_t iteration_ = 0;
  std::map<uint64_t, wire::Job> jobs_;
  std::map<uint64_t, std::vector<FoundPoint>> results_;
  std::map<std::string, double> kernel_seconds_;
  std::map<std::string, int64_t> points_by_worker_;
  std::map<uint64_t, std::string> last_failure_;
  int32_t bad_jobs_ = 0;
  int32_t skipped_ = 0;
  int32_t requeued_ = 0;
  std::map<std::string, int64_t> iteration_counts_;
  double seconds_jobs_ = 0;
  double sweep_started_ = 0;
  double sweep_seconds_ = 0;
  std::string kernel_;
  std::set<std::string> warned_kernels_;
};

Coordinator::Coordinator(const CoordinatorOptions& options, ServerTransport* transport)
    : impl_(std::make_unique<Impl>(options, transport)) {}

Coordinator::~Coordinator() = default;

CoordinatorResult Coordinator::Run(const std::function<bool()>& stop_requested) {
  return impl_->Run(stop_requested);
}

}  // namespace ms
