// An in-memory transport for tests: one server, any number of clients, unbounded queues,
// thread-safe, behind the same interfaces as ZeroMQ (proto/transport.h). Destroying a client
// drops the messages addressed to it, like a dead TCP peer.
#pragma once

#include <memory>

#include "proto/transport.h"

namespace ms {

struct InMemoryQueues;  // the queues and their lock, shared by the network and its ends

class InMemoryNetwork {
 public:
  static std::shared_ptr<InMemoryNetwork> Create();
  // The server end (one per network; a second call fails an MS_CHECK).
  std::unique_ptr<ServerTransport> Bind();
  // A new client with a fresh peer identity ("peer-1", "peer-2", ...).
  std::unique_ptr<ClientTransport> Connect();

 private:
  InMemoryNetwork();
  std::shared_ptr<InMemoryQueues> queues_;
};

}  // namespace ms
