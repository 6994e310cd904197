#include "proto/transport.h"

#include <chrono>

#include "base/check.h"

namespace ms {

class InMemoryServer : public ServerTransport {
 public:
  explicit InMemoryServer(std::shared_ptr<InMemoryNetwork> network)
      : network_(std::move(network)) {}
  bool Receive(double timeout_s, PeerMessage* message) override {
    return network_->Pop(&network_->to_server_, timeout_s, message);
  }
  void Send(const std::string& peer, const std::string& payload) override {
    std::lock_guard<std::mutex> lock(network_->mutex_);
    auto it = network_->to_client_.find(peer);
    if (it == network_->to_client_.end()) return;  // gone: dropped, as ROUTER does
    it->second.push_back(PeerMessage{peer, payload, 1});
    network_->changed_.notify_all();
  }
  std::string Endpoint() const override { return "inmemory://"; }

 private:
  std::shared_ptr<InMemoryNetwork> network_;
};

class InMemoryClient : public ClientTransport {
 public:
  InMemoryClient(std::shared_ptr<InMemoryNetwork> network, std::string peer)
      : network_(std::move(network)), peer_(std::move(peer)) {}
  ~InMemoryClient() override {
    std::lock_guard<std::mutex> lock(network_->mutex_);
    network_->to_client_.erase(peer_);
  }
  bool Receive(double timeout_s, std::string* payload) override {
    PeerMessage message;
    std::deque<PeerMessage>* queue;
    {
      std::lock_guard<std::mutex> lock(network_->mutex_);
      queue = &network_->to_client_[peer_];
    }
    if (!network_->Pop(queue, timeout_s, &message)) return false;
    *payload = std::move(message.payload);
    return true;
  }
  void Send(const std::string& payload) override {
    std::lock_guard<std::mutex> lock(network_->mutex_);
    network_->to_server_.push_back(PeerMessage{peer_, payload, 1});
    network_->changed_.notify_all();
  }

 private:
  std::shared_ptr<InMemoryNetwork> network_;
  std::string peer_;
};

std::shared_ptr<InMemoryNetwork> InMemoryNetwork::Create() {
  return std::shared_ptr<InMemoryNetwork>(new InMemoryNetwork());
}

std::unique_ptr<ServerTransport> InMemoryNetwork::Bind() {
  std::lock_guard<std::mutex> lock(mutex_);
  MS_CHECK(!bound_) << "InMemoryNetwork: the server end is already bound";
  bound_ = true;
  return std::make_unique<InMemoryServer>(shared_from_this());
}

std::unique_ptr<ClientTransport> InMemoryNetwork::Connect() {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string peer = "peer-" + std::to_string(next_peer_++);
  to_client_[peer];
  return std::make_unique<InMemoryClient>(shared_from_this(), peer);
}

bool InMemoryNetwork::Pop(std::deque<PeerMessage>* queue, double timeout_s, PeerMessage* message) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::microseconds(static_cast<int64_t>(timeout_s * 1e6));
  while (queue->empty()) {
    if (changed_.wait_until(lock, deadline) == std::cv_status::timeout && queue->empty()) {
      return false;
    }
  }
  *message = std::move(queue->front());
  queue->pop_front();
  return true;
}

}  // namespace ms
