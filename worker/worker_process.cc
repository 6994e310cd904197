#include "worker/worker_process.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <thread>
#include <tuple>
#include <vector>

#include "base/error.h"
#include "base/log.h"
#include "proto/content_hash.h"
#include "proto/options_codec.h"
#include "refine/gradient_kernel.h"
#include "refine/refine_wire.h"
#include "refine/refiner.h"
#include "worker/job_codec.h"

namespace ms {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string DefaultWorkerId() {
  char host[256] = {0};
  if (gethostname(host, sizeof(host) - 1) != 0) std::snprintf(host, sizeof(host), "unknown");
  return fmt::format("{}:{}", host, getpid());
}

ImageRef RefFromWire(const wire::ImageRef& w) {
  return ImageRef{w.path(), w.content_hash(), w.byte_size()};
}

}  // namespace

void WorkerOptions::Check() const {
  CheckOptionGroup(*this);
  if (reconnect_max_s < reconnect_initial_s) {
    throw InputError(fmt::format("--reconnect-max must be >= --reconnect-initial ({}), got {}",
                                 reconnect_initial_s, reconnect_max_s));
  }
  cache.Check();
  limits.Check();
}

class Worker::Impl {
 public:
  Impl(const WorkerOptions& options, ClientTransportFactory connect,
       std::unique_ptr<SweepKernel> kernel)
      : options_(options),
        connect_(std::move(connect)),
        kernel_(std::move(kernel)),
        cache_(options.cache),
        stamper_(options.id.empty() ? DefaultWorkerId() : options.id) {
    options_.Check();
  }

  ~Impl() {
    if (compute_.joinable()) compute_.join();
  }

  const std::string& id() const { return stamper_.sender(); }

  WorkerSummary Run(const std::function<bool()>& stop_requested) {
    const double silence = options_.liveness * options_.heartbeat_interval_s;
    double backoff = options_.reconnect_initial_s;
    Connect();
    double last_heard = Now(), connected_at = last_heard;
    double next_heartbeat = last_heard + options_.heartbeat_interval_s;
    while (true) {
      if (stop_requested && stop_requested()) {
        summary_.exit_reason = "stopped by signal";
        break;
      }
      FinishComputeIfDone();
      double now = Now();
      const double wait = std::clamp(
          std::min(next_heartbeat - now, phase_ == Phase::kComputing ? 0.01 : 0.05), 0.0, 0.05);
      std::string payload;
      if (transport_->Receive(wait, &payload)) {
        last_heard = Now();
        backoff = options_.reconnect_initial_s;
        if (!Handle(payload)) break;  // shutdown
      }
      const std::string refused = transport_->AuthFailure();
      if (!refused.empty()) {
        throw InputError(refused + "; check --curve-secret-key here and --curve-public-keys there");
      }
      now = Now();
      if (now >= next_heartbeat) {
        SendHeartbeat();
        next_heartbeat = now + options_.heartbeat_interval_s;
      }
      if (now - std::max(last_heard, connected_at) > silence) {
        if (now - last_heard > options_.give_up_after_s) {
          throw InputError(fmt::format(
              "no coordinator answered for {:.0f} s (--give-up-after {:.0f} s); giving up (is "
              "it running, is the address right, and do both sides agree on CURVE: "
              "--curve-server-key here iff --curve-secret-key there, with its public key?)",
              now - last_heard, options_.give_up_after_s));
        }
        spdlog::warn("no message from the coordinator for {:.1f} s; reconnecting in {:.1f} s",
                     now - last_heard, backoff);
        if (phase_ == Phase::kFetching) {
          // The coordinator requeues it (our heartbeats will say we are idle).
          phase_ = Phase::kIdle;
          current_.reset();
        }
        transport_.reset();
        const double until = Now() + backoff;
        while (Now() < until && !(stop_requested && stop_requested())) {
          std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        backoff = std::min(2 * backoff, options_.reconnect_max_s);
        Connect();
        ++summary_.reconnects;
        connected_at = Now();
        next_heartbeat = connected_at + options_.heartbeat_interval_s;
      }
    }
    if (compute_.joinable()) {
      if (phase_ == Phase::kComputing) {
        spdlog::info("waiting for the current sweep to finish before exiting");
      }
      compute_.join();
    }
    transport_.reset();
    const ImageCache::Stats cache = cache_.stats();
    spdlog::info(
        "worker {} exits ({}): {} jobs, {} failed, {} points, {} reconnects; images: {} local, "
        "{} cached, {} fetched, {} decoded, {} from memory",
        id(), summary_.exit_reason, summary_.jobs, summary_.failed_jobs, summary_.points,
        summary_.reconnects, cache.local_hits, cache.disk_hits, cache.stored, cache.decoded,
        cache.memory_hits);
    return summary_;
  }

 private:
  enum class Phase { kIdle, kFetching, kComputing };

  // A refinement job: the pair (sweep.camera, sweep.neighbours[0]) at a pyramid level.
  struct RefinePair {
    int level = 0;
    RefineOptions options;
  };

  struct Current {
    wire::Job job;
    SweepJob sweep;                    // views, mesh, options; images filled by the compute thread
    std::optional<RefinePair> refine;  // set for refinement jobs (sweep.options unused)
    std::vector<ImageRef> refs;        // one per camera: C, then the neighbours
    std::vector<std::string> paths;    // local file of each camera's image ("" until fetched)
    size_t fetch = 0;                  // index into refs being fetched
    std::string buffer;                // bytes fetched so far
    double received_at = 0;
    double fetch_s = 0;
  };

  void Send(wire::Envelope& envelope) {
    if (transport_) transport_->Send(Serialize(envelope));
  }

  void Connect() {
    transport_ = connect_();
    if (phase_ != Phase::kIdle) {
      // Busy (fetching images or computing), maybe for a coordinator that has since restarted:
      // a heartbeat says so, and the result will say when we are idle. A Ready here would get
      // us a second job, refused as "busy", which would count against that job's attempts.
      SendHeartbeat();
      return;
    }
    wire::Envelope envelope = stamper_.New();
    wire::Ready* ready = envelope.mutable_ready();
    ready->set_worker_id(id());
    ready->set_kernel(kernel_->Name());
    char host[256] = {0};
    gethostname(host, sizeof(host) - 1);
    ready->set_hostname(host);
    ready->set_pid(static_cast<uint32_t>(getpid()));
    ready->set_threads(std::max(1u, std::thread::hardware_concurrency()));
    Send(envelope);
  }

  void SendHeartbeat() {
    wire::Envelope envelope = stamper_.New();
    wire::Heartbeat* heartbeat = envelope.mutable_heartbeat();
    if (phase_ != Phase::kIdle && current_) {
      heartbeat->set_current_job_id(current_->job.job_id());
      heartbeat->set_session_id(current_->job.session_id());
    }
    heartbeat->set_last_job_id(last_job_id_);
    Send(envelope);
  }

  wire::Envelope ErrorEnvelope(wire::Error::Code code, uint64_t job_id, uint64_t session,
                               const std::string& message) {
    wire::Envelope envelope = stamper_.New();
    wire::Error* error = envelope.mutable_error();
    error->set_code(code);
    error->set_job_id(job_id);
    error->set_session_id(session);
    error->set_message(message);
    return envelope;
  }

  void SendError(wire::Error::Code code, uint64_t job_id, uint64_t session,
                 const std::string& message) {
    wire::Envelope envelope = ErrorEnvelope(code, job_id, session, message);
    Send(envelope);
  }

  void FailCurrent(wire::Error::Code code, const std::string& message) {
    spdlog::warn("job {}: {}", JobName(current_->job.job_id()), message);
    SendError(code, current_->job.job_id(), current_->job.session_id(), message);
    ++summary_.failed_jobs;
    phase_ = Phase::kIdle;
    current_.reset();
  }

  // Returns false on Shutdown.
  bool Handle(const std::string& payload) {
    wire::Envelope envelope;
    std::string problem;
    const DecodeStatus status =
        DecodeEnvelope(payload.data(), payload.size(), options_.limits, &envelope, &problem);
    if (status == DecodeStatus::kWrongVersion) {
      throw InputError("the coordinator speaks another protocol: " + problem +
                       "; run the same manisweep version on both sides");
    }
    if (status != DecodeStatus::kOk) {
      spdlog::warn("dropped a message from the coordinator: {}", problem);
      return true;
    }
    switch (envelope.body_case()) {
      case wire::Envelope::kHeartbeat:
        return true;
      case wire::Envelope::kJob:
        OnJob(std::move(*envelope.mutable_job()));
        return true;
      case wire::Envelope::kImageResponse:
        OnImageResponse(envelope.image_response());
        return true;
      case wire::Envelope::kShutdown:
        summary_.exit_reason = "shutdown: " + envelope.shutdown().reason();
        return false;
      case wire::Envelope::kError:
        if (envelope.error().code() == wire::Error::VERSION_MISMATCH) {
          throw InputError("the coordinator refused this worker: " + envelope.error().message());
        }
        spdlog::warn("the coordinator says: {}", envelope.error().message());
        return true;
      default:
        spdlog::warn("dropped an unexpected {} message from the coordinator", BodyName(envelope));
        return true;
    }
  }

  void OnJob(wire::Job&& job) {
    if (phase_ != Phase::kIdle) {
      wire::Envelope envelope = ErrorEnvelope(
          wire::Error::BUSY, job.job_id(), job.session_id(),
          fmt::format("busy with job {}", current_ ? JobName(current_->job.job_id()) : "?"));
      if (current_) {
        envelope.mutable_error()->set_busy_job_id(current_->job.job_id());
        envelope.mutable_error()->set_busy_session_id(current_->job.session_id());
      }
      Send(envelope);
      return;
    }
    last_job_id_ = job.job_id();
    current_.emplace();
    Current& c = *current_;
    c.received_at = Now();
    c.job = std::move(job);
    const std::string what =
        fmt::format("job {} (iteration {}, camera {})", JobName(c.job.job_id()), c.job.iteration(),
                    c.job.camera().id());
    phase_ = Phase::kFetching;
    try {
      c.sweep.camera.id = c.job.camera().id();
      c.sweep.camera.view = ViewFromWire(c.job.camera(), what);
      c.refs.push_back(RefFromWire(c.job.camera().image()));
      for (const wire::JobCamera& n : c.job.neighbours()) {
        SweepCamera camera;
        camera.id = n.id();
        camera.view = ViewFromWire(n, what);
        c.sweep.neighbours.push_back(std::move(camera));
        c.refs.push_back(RefFromWire(n.image()));
      }
      if (c.job.has_refine() && c.job.refine().mesh_id() != 0 && c.job.mesh().num_vertices() == 0) {
        // The round's mesh, received with an earlier job of this round.
        if (mesh_id_ != c.job.refine().mesh_id() || mesh_session_ != c.job.session_id()) {
          spdlog::info("{}: asking for the round's mesh {}, which this worker does not hold", what,
                       c.job.refine().mesh_id());
          SendError(wire::Error::NEED_MESH, c.job.job_id(), c.job.session_id(),
                    fmt::format("no mesh {} here", c.job.refine().mesh_id()));
          phase_ = Phase::kIdle;
          current_.reset();
          return;
        }
        c.sweep.mesh = held_mesh_;
      } else {
        c.sweep.mesh = UnpackMesh(c.job.mesh(), what);
        if (c.job.has_refine() && c.job.refine().mesh_id() != 0) {
          held_mesh_ = c.sweep.mesh;
          mesh_id_ = c.job.refine().mesh_id();
          mesh_session_ = c.job.session_id();
        }
      }
      if (c.job.has_refine()) {
        c.refine = ReadRefinePair(c.job, what);
      } else {
        c.sweep.options = OptionsFromWire<SweepOptions>(c.job.options());
        c.sweep.options.Check();
      }
      c.sweep.iteration = c.job.iteration();
    } catch (const InputError& e) {
      FailCurrent(wire::Error::BAD_JOB, e.what());
      return;
    }
    spdlog::info("{} started: {} neighbours, {} faces", what, c.sweep.neighbours.size(),
                 c.sweep.mesh.NumFaces());
    if (!NeedsImages(c)) {
      c.fetch_s = 0;
      StartCompute();
      return;
    }
    for (const ImageRef& ref : c.refs) {
      if (ref.hash == 0 && ref.size == 0) {
        FailCurrent(wire::Error::BAD_JOB,
                    "the job carries no image (the coordinator runs with --no-images); only "
                    "--kernel replay takes such jobs, and no refinement job");
        return;
      }
    }
    for (const ImageRef& ref : c.refs) c.paths.push_back(cache_.Locate(ref));
    c.fetch = 0;
    NextFetchOrCompute();
  }

  // Refinement compares images whatever the sweep kernel (the replay kernel included).
  bool NeedsImages(const Current& c) const { return c.refine || kernel_->NeedsImages(); }

  // The gradient kernel `name` asks for, made on first use (on the compute thread: a GLSL
  // kernel's context is bound only while it computes) and kept while jobs ask for the same.
  PairGradientKernel& RefineKernel(const std::string& name) {
    if (!refine_kernel_ || refine_kernel_asked_ != name) {
      std::string why;
      refine_kernel_ = MakePairGradientKernel(name, &why);
      refine_kernel_asked_ = name;
      spdlog::info("worker {}: refinement kernel {} ({})", id(), refine_kernel_->Name(), why);
    }
    return *refine_kernel_;
  }

  // Camera `index` of refinement job `c` (0: the reference, 1: the neighbour) at the job's
  // level, made once per round's level: a round asks for each camera twice or more, and scaling
  // a full-size image takes about as long as a coarse level's gradient.
  const RefineView& LevelView(const Current& c, size_t index) {
    const SweepCamera& camera = index == 0 ? c.sweep.camera : c.sweep.neighbours[index - 1];
    const LevelViewKey key{c.job.session_id(), camera.id, c.refs[index].hash, c.refine->level};
    if (!level_views_.empty() && std::get<3>(level_views_.begin()->first) != c.refine->level) {
      level_views_.clear();  // a new level: the old views are done with
    }
    auto it = level_views_.find(key);
    if (it == level_views_.end()) {
      it = level_views_.emplace(key, RefineViewAtLevel(camera, c.refine->level)).first;
    }
    return it->second;
  }

  static RefinePair ReadRefinePair(const wire::Job& job, const std::string& what) {
    RefinePair pair;
    pair.level = job.refine().pyramid_level();
    if (pair.level < 0 || pair.level > 16) {
      throw InputError(
          fmt::format("{}: refinement pyramid level {} is not in [0, 16]", what, pair.level));
    }
    if (job.neighbours_size() != 1) {
      throw InputError(fmt::format("{}: a refinement job needs exactly one neighbour, it has {}",
                                   what, job.neighbours_size()));
    }
    pair.options = OptionsFromWire<RefineOptions>(job.refine().options());
    pair.options.Check();
    return pair;
  }

  void NextFetchOrCompute() {
    Current& c = *current_;
    while (c.fetch < c.refs.size() && !c.paths[c.fetch].empty()) ++c.fetch;
    if (c.fetch == c.refs.size()) {
      c.fetch_s = Now() - c.received_at;
      StartCompute();
      return;
    }
    if (c.refs[c.fetch].size > (uint64_t{4} << 30)) {
      FailCurrent(wire::Error::BAD_JOB, c.refs[c.fetch].path + ": image over 4 GiB");
      return;
    }
    c.buffer.clear();
    c.buffer.reserve(c.refs[c.fetch].size);
    spdlog::info("fetching {} ({} bytes, hash {}) from the coordinator", c.refs[c.fetch].path,
                 c.refs[c.fetch].size, HashHex(c.refs[c.fetch].hash));
    RequestChunk();
  }

  void RequestChunk() {
    const Current& c = *current_;
    wire::Envelope envelope = stamper_.New();
    wire::ImageRequest* request = envelope.mutable_image_request();
    request->set_content_hash(c.refs[c.fetch].hash);
    request->set_offset(c.buffer.size());
    request->set_max_bytes(options_.limits.image_chunk_bytes);
    Send(envelope);
  }

  void OnImageResponse(const wire::ImageResponse& response) {
    if (phase_ != Phase::kFetching || !current_) return;  // late: we gave up on that job
    Current& c = *current_;
    const ImageRef& ref = c.refs[c.fetch];
    if (response.content_hash() != ref.hash || response.offset() != c.buffer.size()) return;
    if (!response.found()) {
      FailCurrent(wire::Error::WORKER_FAILURE,
                  fmt::format("the coordinator cannot serve {} (hash {}): {}", ref.path,
                              HashHex(ref.hash), response.error()));
      return;
    }
    if (response.total_size() != ref.size || response.data().empty() ||
        c.buffer.size() + response.data().size() > ref.size) {
      FailCurrent(wire::Error::WORKER_FAILURE,
                  fmt::format("{}: inconsistent image response (size {}, piece {} at {})", ref.path,
                              response.total_size(), response.data().size(), response.offset()));
      return;
    }
    c.buffer += response.data();
    if (c.buffer.size() < ref.size) {
      RequestChunk();
      return;
    }
    std::string stored;
    try {
      stored = cache_.Store(ref, c.buffer);
    } catch (const InputError& e) {
      FailCurrent(wire::Error::WORKER_FAILURE, e.what());
      return;
    }
    ++summary_.images_fetched;
    std::string().swap(c.buffer);
    for (size_t i = 0; i < c.refs.size(); ++i) {
      if (c.refs[i].hash == ref.hash && c.refs[i].size == ref.size) c.paths[i] = stored;
    }
    NextFetchOrCompute();
  }

  void StartCompute() {
    phase_ = Phase::kComputing;
    compute_done_ = false;
    if (compute_.joinable()) compute_.join();
    outcome_ = wire::Envelope();
    compute_ = std::thread([this] { Compute(); });
  }

  // On the compute thread: only touches current_ (the main thread leaves it alone while
  // computing), the cache (thread-safe), the kernel and outcome_.
  void Compute() {
    Current& c = *current_;
    const uint64_t job_id = c.job.job_id();
    try {
      Timer images;
      if (NeedsImages(c)) {
        const View camera_view = c.sweep.camera.view;
        c.sweep.camera = cache_.Load(c.sweep.camera.id, camera_view, c.refs[0].hash, c.paths[0]);
        for (size_t i = 0; i < c.sweep.neighbours.size(); ++i) {
          SweepCamera& n = c.sweep.neighbours[i];
          const View view = n.view;
          n = cache_.Load(n.id, view, c.refs[i + 1].hash, c.paths[i + 1]);
        }
      }
      const double images_s = c.fetch_s + images.Seconds();
      if (options_.debug_delay_s > 0) {
        std::this_thread::sleep_for(std::chrono::duration<double>(options_.debug_delay_s));
      }
      Timer sweep;
      wire::Result* out = outcome_.mutable_result();
      if (c.refine) {
        const RefineView& reference = LevelView(c, 0);
        const RefineView& neighbour = LevelView(c, 1);
        PairGradientKernel& kernel = RefineKernel(c.refine->options.kernel);
        PairGradientToWire(kernel.Compute(c.sweep.mesh, reference, neighbour, c.refine->options),
                           out->mutable_gradient());
      } else {
        SweepResultToWire(kernel_->Run(c.sweep), out);
      }
      out->set_job_id(job_id);
      out->set_iteration(c.job.iteration());
      out->set_session_id(c.job.session_id());
      out->set_worker_id(id());
      out->set_kernel(c.refine ? refine_kernel_->Name() : kernel_->Name());
      out->set_images_seconds(images_s);
      out->set_sweep_seconds(sweep.Seconds());
    } catch (const InputError& e) {
      wire::Error* error = outcome_.mutable_error();
      error->set_code(wire::Error::BAD_JOB);
      error->set_message(e.what());
    } catch (const std::exception& e) {
      wire::Error* error = outcome_.mutable_error();
      error->set_code(wire::Error::WORKER_FAILURE);
      error->set_message(fmt::format("{}: {}", kernel_->Name(), e.what()));
    }
    compute_done_ = true;
  }

  void FinishComputeIfDone() {
    if (phase_ != Phase::kComputing || !compute_done_ || !transport_) return;
    compute_.join();
    Current& c = *current_;
    wire::Envelope envelope = stamper_.New();
    if (outcome_.has_result()) {
      wire::Result* result = envelope.mutable_result();
      result->Swap(outcome_.mutable_result());
      result->set_total_seconds(Now() - c.received_at);
      spdlog::info("job {} (iteration {}, camera {}): {}; images {:.2f} s, {} {:.2f} s",
                   JobName(c.job.job_id()), c.job.iteration(), c.job.camera().id(),
                   c.refine ? fmt::format("gradient over {} pixels", result->gradient().pixels())
                            : fmt::format("{} points", result->points_size()),
                   result->images_seconds(), c.refine ? "gradient" : "sweep",
                   result->sweep_seconds());
      ++summary_.jobs;
      summary_.points += result->points_size();
    } else {
      wire::Error* error = envelope.mutable_error();
      error->Swap(outcome_.mutable_error());
      error->set_job_id(c.job.job_id());
      error->set_session_id(c.job.session_id());
      spdlog::warn("job {} failed: {}", JobName(c.job.job_id()), error->message());
      ++summary_.failed_jobs;
    }
    Send(envelope);
    phase_ = Phase::kIdle;
    current_.reset();
  }

  WorkerOptions options_;
  ClientTransportFactory connect_;
  std::unique_ptr<SweepKernel> kernel_;
  std::unique_ptr<PairGradientKernel> refine_kernel_;  // compute thread only
  std::string refine_kernel_asked_;
  // Session, camera, image hash, level (compute thread only).
  using LevelViewKey = std::tuple<uint64_t, int32_t, uint64_t, int>;
  std::map<LevelViewKey, RefineView> level_views_;
  ImageCache cache_;
  EnvelopeStamper stamper_;
  std::unique_ptr<ClientTransport> transport_;
  WorkerSummary summary_;
  Phase phase_ = Phase::kIdle;
  std::optional<Current> current_;
  uint64_t last_job_id_ = 0;
  // The refinement round's mesh, as its first job here brought it (main thread only).
  Mesh held_mesh_;
  uint64_t mesh_id_ = 0, mesh_session_ = 0;
  std::thread compute_;
  std::atomic<bool> compute_done_{false};
  wire::Envelope outcome_;
};

Worker::Worker(const WorkerOptions& options, ClientTransportFactory connect,
               std::unique_ptr<SweepKernel> kernel)
    : impl_(std::make_unique<Impl>(options, std::move(connect), std::move(kernel))) {}

Worker::~Worker() = default;

WorkerSummary Worker::Run(const std::function<bool()>& stop_requested) {
  return impl_->Run(stop_requested);
}

const std::string& Worker::id() const { return impl_->id(); }

}  // namespace ms
