// What the coordinator's network loops share (the sweep run's and refinement's): the clock,
// session ids, how peers appear in logs, rate-limited warnings about junk, and the handling of
// the messages both take alike.
#pragma once

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>

#include "coordinator/image_catalog.h"
#include "coordinator/job_scheduler.h"
#include "proto/content_hash.h"
#include "proto/transport.h"
#include "proto/wire.h"

namespace ms {

// A worker busy with a job of another session (a coordinator before a restart, or the sweep
// run before refinement): the scheduler keeps it out of the idle pool until it reports.
constexpr uint64_t kForeignJob = std::numeric_limits<uint64_t>::max();

inline double MonotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Random per coordinator start: results of an older session are stale.
inline uint64_t NewSessionId() {
  std::random_device random;
  const uint64_t session =
      (uint64_t{random()} << 32) ^ random() ^ static_cast<uint64_t>(MonotonicSeconds() * 1e6);
  return session == 0 ? 1 : session;
}

// Results that do not fit their jobs before a worker is sent away.
constexpr int kMaxUnfitResults = 3;

// Workers whose results keep not fitting their jobs are buggy or hostile: after
// kMaxUnfitResults of them a worker is told to shut down, leaves the scheduler, and its later
// messages are dropped (CURVE is what keeps strangers out).
class UnfitWorkers {
 public:
  // Counts one unfit result of `peer`; at the limit sends it away.
  void Note(const std::string& peer, const std::string& sender, JobScheduler* scheduler,
            ServerTransport* transport, EnvelopeStamper* stamper);
  bool SentAway(const std::string& peer) const { return sent_away_.count(peer) > 0; }

 private:
  std::map<std::string, int> unfit_results_;
  std::set<std::string> sent_away_;
};

// Transport identities are binary; logs show a short hash.
inline std::string PeerTag(const std::string& peer) {
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

// Decodes one message from a worker for a coordinator's loop. A message of several frames, or
// one that does not parse, is dropped and logged through `junk`; one of another protocol
// version is answered with Error VERSION_MISMATCH and logged, and `*wrong_version` set (the
// caller forgets the peer). Returns true when `envelope` is usable.
bool DecodeWorkerMessage(const PeerMessage& message, const WireLimits& limits,
                         ServerTransport* transport, EnvelopeStamper* stamper, JunkLog* junk,
                         wire::Envelope* envelope, bool* wrong_version);

// The job a heartbeat says its worker is busy with, for the scheduler: 0 (idle), the job, or
// kForeignJob when it is a job of another session.
inline uint64_t HeartbeatJob(const wire::Heartbeat& heartbeat, uint64_t session) {
  if (heartbeat.current_job_id() == 0 || heartbeat.session_id() == session) {
    return heartbeat.current_job_id();
  }
  return kForeignJob;
}

// The job a BUSY error says its worker is on, for the scheduler: the job, or kForeignJob when
// it is another session's or not named (the worker is busy all the same).
inline uint64_t BusyJob(const wire::Error& error, uint64_t session) {
  if (error.busy_job_id() != 0 && error.busy_session_id() == session) return error.busy_job_id();
  return kForeignJob;
}

// What both loops do with an Error before their own codes. BUSY: the worker is on another
// job and stays out of the idle pool. Not `ours` (no job of this round): logged, and the
// worker's state updated. `job_label` names the job in the log ("job …"). Returns whether
// `error` was handled.
bool HandleBusyOrForeignError(const wire::Error& error, bool ours, const std::string& job_label,
                              uint64_t session, const std::string& peer, const std::string& sender,
                              double now, JobScheduler* scheduler);

// Answers an ImageRequest from `catalog` (null: the coordinator is still starting) and logs
// a refusal, or the start of a file's transfer.
void ServeImageRequest(const ImageCatalog* catalog, const wire::ImageRequest& request,
                       const std::string& peer, const std::string& sender, const WireLimits& limits,
                       ServerTransport* transport, EnvelopeStamper* stamper);

// What a network loop does with the messages that differ between the sweep run and refinement.
class WorkerMessageHandler {
 public:
  virtual ~WorkerMessageHandler() = default;
  virtual void OnReady(const std::string& peer, const std::string& sender, const wire::Ready& ready,
                       double now) = 0;
  virtual void OnResult(const std::string& peer, const std::string& sender,
                        const wire::Result& result, double now) = 0;
  virtual void OnError(const std::string& peer, const std::string& sender, const wire::Error& error,
                       double now) = 0;
  // Before a heartbeat of a peer the scheduler does not know yet.
  virtual void OnHeartbeatOfNewcomer(const std::string& sender) { (void)sender; }
};

// One message from a worker through what both network loops do alike: decode it (junk dropped,
// another protocol version answered and the peer forgotten), keep heartbeats, serve image
// requests (`catalog`: null while the coordinator is starting), drop unexpected bodies; Ready,
// Result and Error go to `handler`.
struct WorkerMessageContext {
  const WireLimits& limits;
  ServerTransport* transport;
  EnvelopeStamper* stamper;
  JunkLog* junk;
  JobScheduler* scheduler;
  uint64_t session;
};
void RouteWorkerMessage(const PeerMessage& message, double now, const ImageCatalog* catalog,
                        const WorkerMessageContext& context, WorkerMessageHandler* handler);

// One turn of a coordinator's network loop, the same for the sweep run and refinement: waits
// up to 20 ms for a message, hands it and up to 100 queued ones to `handle` (draining without
// starving the periodic work), then expires leases and silent workers and sends the heartbeats
// due. Returns the time of the periodic work and what expired, for the caller's logs.
struct NetworkTurn {
  double now = 0;
  JobScheduler::Expiry expiry;
};
NetworkTurn TurnNetwork(ServerTransport* transport, JobScheduler* scheduler,
                        EnvelopeStamper* stamper,
                        const std::function<void(const PeerMessage&)>& handle);

}  // namespace ms
