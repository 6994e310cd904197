#include "testing/in_memory_network.h"

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>

#include "base/check.h"

namespace ms {

struct InMemoryQueues {
  std::mutex mutex;
  std::condition_variable changed;
  bool bound = false;
  int next_peer = 1;
  std::deque<PeerMessage> to_server;
  std::map<std::string, std::deque<PeerMessage>> to_client;  // by peer; erased when gone

  // Waits up to timeout_s for a message in `queue` (one of the above).
  bool Pop(std::deque<PeerMessage>* queue, double timeout_s, PeerMessage* message) {
    std::unique_lock<std::mutex> lock(mutex);
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::microseconds(static_cast<int64_t>(timeout_s * 1e6));
    while (queue->empty()) {
      if (changed.wait_until(lock, deadline) == std::cv_status::timeout && queue->empty()) {
        return false;
      }
    }
    *message = std::move(queue->front());
    queue->pop_front();
    return true;
  }
};

namespace {

class InMemoryServer : public ServerTransport {
 public:
  explicit InMemoryServer(std::shared_ptr<InMemoryQueues> queues) : queues_(std::move(queues)) {}
  bool Receive(double timeout_s, PeerMessage* message) override {
    return queues_->Pop(&queues_->to_server, timeout_s, message);
  }
  void Send(const std::string& peer, const std::string& payload) override {
    std::lock_guard<std::mutex> lock(queues_->mutex);
    auto it = queues_->to_client.find(peer);
    if (it == queues_->to_client.end()) return;  // gone: dropped, as ROUTER does
    it->second.push_back(PeerMessage{peer, payload, 1});
    queues_->changed.notify_all();
  }
  std::string Endpoint() const override { return "inmemory://"; }

 private:
  std::shared_ptr<InMemoryQueues> queues_;
};

class InMemoryClient : public ClientTransport {
 public:
  InMemoryClient(std::shared_ptr<InMemoryQueues> queues, std::string peer)
      : queues_(std::move(queues)), peer_(std::move(peer)) {}
  ~InMemoryClient() override {
    std::lock_guard<std::mutex> lock(queues_->mutex);
    queues_->to_client.erase(peer_);
  }
  bool Receive(double timeout_s, std::string* payload) override {
    PeerMessage message;
    std::deque<PeerMessage>* queue;
    {
      std::lock_guard<std::mutex> lock(queues_->mutex);
      queue = &queues_->to_client[peer_];
    }
    if (!queues_->Pop(queue, timeout_s, &message)) return false;
    *payload = std::move(message.payload);
    return true;
  }
  void Send(const std::string& payload) override {
    std::lock_guard<std::mutex> lock(queues_->mutex);
    queues_->to_server.push_back(PeerMessage{peer_, payload, 1});
    queues_->changed.notify_all();
  }

 private:
  std::shared_ptr<InMemoryQueues> queues_;
  std::string peer_;
};

}  // namespace

InMemoryNetwork::InMemoryNetwork() : queues_(std::make_shared<InMemoryQueues>()) {}

std::shared_ptr<InMemoryNetwork> InMemoryNetwork::Create() {
  return std::shared_ptr<InMemoryNetwork>(new InMemoryNetwork());
}

std::unique_ptr<ServerTransport> InMemoryNetwork::Bind() {
  std::lock_guard<std::mutex> lock(queues_->mutex);
  MS_CHECK(!queues_->bound) << "InMemoryNetwork: the server end is already bound";
  queues_->bound = true;
  return std::make_unique<InMemoryServer>(queues_);
}

std::unique_ptr<ClientTransport> InMemoryNetwork::Connect() {
  std::lock_guard<std::mutex> lock(queues_->mutex);
  const std::string peer = "peer-" + std::to_string(queues_->next_peer++);
  queues_->to_client[peer];
  return std::make_unique<InMemoryClient>(queues_, peer);
}

}  // namespace ms
