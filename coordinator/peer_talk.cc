#include "coordinator/peer_talk.h"

namespace ms {

void UnfitWorkers::Note(const std::string& peer, const std::string& sender, JobScheduler* scheduler,
                        ServerTransport* transport, EnvelopeStamper* stamper) {
  if (++unfit_results_[peer] < kMaxUnfitResults) return;
  spdlog::warn("worker {} ({}) sent {} results that do not fit their jobs: sending it away", sender,
               PeerTag(peer), kMaxUnfitResults);
  wire::Envelope envelope = stamper->New();
  envelope.mutable_shutdown()->set_reason("its results do not fit the jobs handed out");
  transport->Send(peer, Serialize(envelope));
  scheduler->Remove(peer);
  sent_away_.insert(peer);
}

bool HandleBusyOrForeignError(const wire::Error& error, bool ours, const std::string& job_label,
                              uint64_t session, const std::string& peer, const std::string& sender,
                              double now, JobScheduler* scheduler) {
  if (error.code() == wire::Error::BUSY) {
    spdlog::info("worker {} did not take {}: {}", sender, job_label, error.message());
    scheduler->OnBusy(peer, sender, error.job_id(), BusyJob(error, session), now);
    return true;
  }
  if (ours) return false;
  scheduler->Touch(peer, sender, now);
  if (error.job_id() != 0) scheduler->OnResult(peer, sender, kForeignJob, now);
  spdlog::warn("worker {} reports: {}", sender, error.message());
  return true;
}

bool DecodeWorkerMessage(const PeerMessage& message, const WireLimits& limits,
                         ServerTransport* transport, EnvelopeStamper* stamper, JunkLog* junk,
                         wire::Envelope* envelope, bool* wrong_version) {
  *wrong_version = false;
  const std::string who = PeerTag(message.peer);
  if (message.frames != 1) {
    junk->Warn("frames", fmt::format("dropped a message of {} frames from {} (expected 1)",
                                     message.frames, who));
    return false;
  }
  std::string problem;
  const DecodeStatus status =
      DecodeEnvelope(message.payload.data(), message.payload.size(), limits, envelope, &problem);
  if (status == DecodeStatus::kWrongVersion) {
    const std::string name = envelope->sender().empty() ? who : envelope->sender();
    junk->Warn("version", fmt::format("refused worker {}: it speaks {}", name, problem));
    wire::Envelope reply = stamper->New();
    wire::Error* error = reply.mutable_error();
    error->set_code(wire::Error::VERSION_MISMATCH);
    error->set_message(fmt::format("this coordinator speaks protocol version {}, you sent {}",
                                   kProtocolVersion, envelope->protocol_version()));
    transport->Send(message.peer, Serialize(reply));
    *wrong_version = true;
    return false;
  }
  if (status != DecodeStatus::kOk) {
    junk->Warn(DecodeStatusName(status), fmt::format("dropped a message from {} ({}): {}", who,
                                                     DecodeStatusName(status), problem));
    return false;
  }
  return true;
}

void ServeImageRequest(const ImageCatalog* catalog, const wire::ImageRequest& request,
                       const std::string& peer, const std::string& sender, const WireLimits& limits,
                       ServerTransport* transport, EnvelopeStamper* stamper) {
  wire::Envelope reply = stamper->New();
  if (catalog != nullptr) {
    catalog->Serve(request.content_hash(), request.offset(), request.max_bytes(),
                   limits.image_chunk_bytes, reply.mutable_image_response());
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
  transport->Send(peer, Serialize(reply));
}

void RouteWorkerMessage(const PeerMessage& message, double now, const ImageCatalog* catalog,
                        const WorkerMessageContext& c, WorkerMessageHandler* handler) {
  wire::Envelope envelope;
  bool wrong_version = false;
  if (!DecodeWorkerMessage(message, c.limits, c.transport, c.stamper, c.junk, &envelope,
                           &wrong_version)) {
    if (wrong_version) c.scheduler->Remove(message.peer);
    return;
  }
  const std::string& sender = envelope.sender();
  switch (envelope.body_case()) {
    case wire::Envelope::kReady:
      handler->OnReady(message.peer, sender, envelope.ready(), now);
      return;
    case wire::Envelope::kHeartbeat:
      if (!c.scheduler->IsKnown(message.peer)) handler->OnHeartbeatOfNewcomer(sender);
      c.scheduler->OnHeartbeat(message.peer, sender, HeartbeatJob(envelope.heartbeat(), c.session),
                               envelope.heartbeat().last_job_id(), now);
      return;
    case wire::Envelope::kResult:
      handler->OnResult(message.peer, sender, envelope.result(), now);
      return;
    case wire::Envelope::kError:
      handler->OnError(message.peer, sender, envelope.error(), now);
      return;
    case wire::Envelope::kImageRequest:
      c.scheduler->Touch(message.peer, sender, now);
      ServeImageRequest(catalog, envelope.image_request(), message.peer, sender, c.limits,
                        c.transport, c.stamper);
      return;
    default:
      c.scheduler->Touch(message.peer, sender, now);
      c.junk->Warn("unexpected", fmt::format("dropped an unexpected {} message from {}",
                                             BodyName(envelope), sender));
      return;
  }
}

NetworkTurn TurnNetwork(ServerTransport* transport, JobScheduler* scheduler,
                        EnvelopeStamper* stamper,
                        const std::function<void(const PeerMessage&)>& handle) {
  PeerMessage message;
  if (transport->Receive(0.02, &message)) {
    handle(message);
    for (int i = 0; i < 100 && transport->Receive(0, &message); ++i) handle(message);
  }
  NetworkTurn turn;
  turn.now = MonotonicSeconds();
  turn.expiry = scheduler->Expire(turn.now);
  for (const std::string& peer : scheduler->DueHeartbeats(turn.now)) {
    wire::Envelope envelope = stamper->New();
    envelope.mutable_heartbeat();
    transport->Send(peer, Serialize(envelope));
  }
  return turn;
}

}  // namespace ms
