// Message transport between the coordinator and its workers, behind small interfaces so that
// the scheduling and protocol logic runs unchanged over ZeroMQ (proto/zmq_transport.h) or over
// an in-memory channel in tests (testing/in_memory_network.h). Payloads are opaque bytes here
// (serialized envelopes, proto/wire.h).
#pragma once

#include <string>

namespace ms {

// One message as the server receives it.
struct PeerMessage {
  std::string peer;     // opaque routing identity of the sender (stable per connection)
  std::string payload;  // the one frame of the message
  int frames = 1;       // frames after the routing identity; a protocol message has exactly 1
};

// The coordinator's side: many peers, messages addressed by peer (a ZeroMQ ROUTER).
class ServerTransport {
 public:
  virtual ~ServerTransport() = default;
  // Waits up to timeout_s for a message. Returns false on timeout.
  virtual bool Receive(double timeout_s, PeerMessage* message) = 0;
  // Queues a message for a peer. A message for a peer that is gone is dropped silently (the
  // protocol's heartbeats and leases detect lost peers).
  virtual void Send(const std::string& peer, const std::string& payload) = 0;
  // Where clients connect (the bound address, with the actual port).
  virtual std::string Endpoint() const = 0;
};

// A worker's side: one server (a ZeroMQ DEALER).
class ClientTransport {
 public:
  virtual ~ClientTransport() = default;
  virtual bool Receive(double timeout_s, std::string* payload) = 0;
  virtual void Send(const std::string& payload) = 0;
  // Non-empty once the transport knows the server refused this client's credentials (CURVE);
  // retrying will not help.
  virtual std::string AuthFailure() const { return ""; }
};

}  // namespace ms
