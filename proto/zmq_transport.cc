#include "proto/zmq_transport.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <zmq.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <zmq.hpp>

#include "base/error.h"
#include "base/file_util.h"
#include "base/text_reader.h"

namespace ms {
namespace fs = std::filesystem;
namespace {

constexpr char kZapEndpoint[] = "inproc://zeromq.zap.01";
constexpr char kZapDomain[] = "manisweep";

// Decodes a Z85 key to its 32 bytes, or returns "" if it is not a valid key.
std::string Z85Decode(const std::string& text) {
  if (text.size() != 40) return "";
  uint8_t key[32];
  if (zmq_z85_decode(key, text.c_str()) == nullptr) return "";
  return std::string(reinterpret_cast<const char*>(key), 32);
}

std::string Z85Encode(const std::string& binary) {
  char text[41];
  if (binary.size() != 32 ||
      zmq_z85_encode(text, reinterpret_cast<const uint8_t*>(binary.data()), 32) == nullptr) {
    return "";
  }
  return std::string(text, 40);
}

void SetBinaryOption(zmq::socket_t& socket, int option, const std::string& value) {
  if (zmq_setsockopt(socket.handle(), option, value.data(), value.size()) != 0) {
    throw InternalError(std::string("zmq_setsockopt: ") + zmq_strerror(zmq_errno()));
  }
}

// Milliseconds to wait in zmq_poll; -1 never happens (callers always pass a timeout).
long PollMs(double seconds) {
  return std::max<long>(0, static_cast<long>(std::ceil(seconds * 1000.0)));
}

// zmq_poll that treats EINTR (a signal: Ctrl-C) as "nothing ready" so callers can look at
// their stop flags.
int Poll(zmq_pollitem_t* items, int count, double timeout_s) {
  const int rc = zmq_poll(items, count, PollMs(timeout_s));
  if (rc < 0) {
    if (zmq_errno() == EINTR) return 0;
    throw InternalError(std::string("zmq_poll: ") + zmq_strerror(zmq_errno()));
  }
  return rc;
}

// Receives all frames of one message without blocking. False if none was ready.
bool ReceiveFrames(zmq::socket_t& socket, std::vector<zmq::message_t>* frames) {
  frames->clear();
  while (true) {
    zmq::message_t frame;
    zmq::recv_result_t got;
    try {
      got = socket.recv(frame, frames->empty() ? zmq::recv_flags::dontwait : zmq::recv_flags::none);
    } catch (const zmq::error_t& e) {
      if (e.num() == EINTR && !frames->empty()) continue;
      if (e.num() == EINTR) return false;
      throw InternalError(std::string("zmq recv: ") + e.what());
    }
    if (!got) return false;
    const bool more = frame.more();
    frames->push_back(std::move(frame));
    if (!more) return true;
  }
}

std::string EventName(uint16_t event) {
  switch (event) {
    case ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL:
      return "handshake failed";
    case ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL:
      return "handshake failed (protocol error)";
    case ZMQ_EVENT_HANDSHAKE_FAILED_AUTH:
      return "handshake refused (authentication)";
    case ZMQ_EVENT_DISCONNECTED:
      return "disconnected";
    default:
      return "event " + std::to_string(event);
  }
}

// A socket monitor: a PAIR socket receiving events of another socket.
class Monitor {
 public:
  Monitor(zmq::context_t& context, zmq::socket_t& watched, const std::string& name, int events)
      : socket_(context, zmq::socket_type::pair) {
    const std::string endpoint = "inproc://monitor-" + name;
    if (zmq_socket_monitor(watched.handle(), endpoint.c_str(), events) != 0) {
      throw InternalError(std::string("zmq_socket_monitor: ") + zmq_strerror(zmq_errno()));
    }
    socket_.connect(endpoint);
  }
  zmq::socket_t& socket() { return socket_; }
  // Reads one event if ready: its code, value and peer address.
  bool Read(uint16_t* event, uint32_t* value, std::string* address) {
    std::vector<zmq::message_t> frames;
    if (!ReceiveFrames(socket_, &frames) || frames.size() != 2 || frames[0].size() != 6) {
      return false;
    }
    std::memcpy(event, frames[0].data(), 2);
    std::memcpy(value, static_cast<const char*>(frames[0].data()) + 2, 4);
    *address = frames[1].to_string();
    return true;
  }

 private:
  zmq::socket_t socket_;
};

// ---- Server

class ZmqServer : public ServerTransport {
 public:
  explicit ZmqServer(const ZmqServerOptions& options)
      : options_(options), context_(1), router_(context_, zmq::socket_type::router) {
    router_.set(zmq::sockopt::linger, 1000);
    router_.set(zmq::sockopt::maxmsgsize,
                static_cast<int64_t>(std::min<uint64_t>(2 * options.max_message_bytes, INT64_MAX)));
    router_.set(zmq::sockopt::sndhwm, 10000);
    router_.set(zmq::sockopt::rcvhwm, 10000);
    const bool curve = !options.curve_secret_key_file.empty();
    if (!curve && !options.curve_public_keys_dir.empty()) {
      throw InputError("--curve-public-keys needs --curve-secret-key (the coordinator's key pair)");
    }
    if (curve) {
      RequireCurve("--curve-secret-key");
      const CurveKeyPair keys = ReadCurveKeyFile(options.curve_secret_key_file, true);
      if (!options.curve_public_keys_dir.empty()) {
        for (const CurveKeyPair& allowed : ReadPublicKeyDirectory(options.curve_public_keys_dir)) {
          allowed_.insert(Z85Decode(allowed.public_key));
        }
        if (allowed_.empty()) {
          throw InputError(options.curve_public_keys_dir +
                           ": no *.key file: no worker could ever connect");
        }
      }
      // The ZAP handler must exist before the first handshake.
      zap_ = std::make_unique<zmq::socket_t>(context_, zmq::socket_type::rep);
      zap_->bind(kZapEndpoint);
      router_.set(zmq::sockopt::zap_domain, kZapDomain);
      router_.set(zmq::sockopt::curve_server, 1);
      SetBinaryOption(router_, ZMQ_CURVE_SECRETKEY, Z85Decode(keys.secret_key));
      spdlog::info("CURVE security on: {} allowed worker key(s){}", allowed_.size(),
                   allowed_.empty() ? " (any worker that knows the server key)" : "");
    }
    monitor_ = std::make_unique<Monitor>(context_, router_, "router",
                                         ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL |
                                             ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL |
                                             ZMQ_EVENT_HANDSHAKE_FAILED_AUTH);
    try {
      router_.bind(options.bind);
    } catch (const zmq::error_t& e) {
      throw InputError("--bind " + options.bind + ": cannot bind: " + e.what());
    }
    endpoint_ = router_.get(zmq::sockopt::last_endpoint);
  }

  bool Receive(double timeout_s, PeerMessage* message) override {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      zmq_pollitem_t items[3] = {{router_.handle(), 0, ZMQ_POLLIN, 0},
                                 {monitor_->socket().handle(), 0, ZMQ_POLLIN, 0},
                                 {zap_ ? zap_->handle() : nullptr, 0, ZMQ_POLLIN, 0}};
      const double left =
          std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
      Poll(items, zap_ ? 3 : 2, std::max(0.0, left));
      if (items[2].revents & ZMQ_POLLIN) HandleZap();
      if (items[1].revents & ZMQ_POLLIN) HandleMonitor();
      if (items[0].revents & ZMQ_POLLIN) {
        std::vector<zmq::message_t> frames;
        if (ReceiveFrames(router_, &frames) && !frames.empty()) {
          message->peer = frames[0].to_string();
          message->frames = static_cast<int>(frames.size()) - 1;
          message->payload = frames.size() >= 2 ? frames[1].to_string() : std::string();
          return true;
        }
      }
      if (std::chrono::steady_clock::now() >= deadline) return false;
    }
  }

  void Send(const std::string& peer, const std::string& payload) override {
    try {
      router_.send(zmq::buffer(peer), zmq::send_flags::sndmore);
      router_.send(zmq::buffer(payload), zmq::send_flags::none);
    } catch (const zmq::error_t& e) {
      // ROUTER drops messages for unknown peers; an error here is a full queue or EINTR.
      spdlog::warn("could not send {} bytes to a worker: {}", payload.size(), e.what());
    }
  }

  std::string Endpoint() const override { return endpoint_; }

 private:
  // ZAP (ZeroMQ RFC 27): decides every CURVE handshake. Frames: version, request id, domain,
  // address, identity, mechanism, client public key.
  void HandleZap() {
    std::vector<zmq::message_t> frames;
    if (!ReceiveFrames(*zap_, &frames)) return;
    if (frames.size() < 6) {
      spdlog::warn("ZAP: malformed request ({} frames)", frames.size());
      return;  // REP would now be stuck; libzmq never sends this
    }
    const std::string version = frames[0].to_string(), request_id = frames[1].to_string();
    const std::string address = frames[3].to_string(), mechanism = frames[5].to_string();
    std::string status = "200", text = "OK";
    if (mechanism != "CURVE" || frames.size() < 7 || frames[6].size() != 32) {
      status = "400";
      text = "CURVE required";
      spdlog::warn("refused a worker from {}: it did not use CURVE (mechanism {})", address,
                   mechanism);
    } else if (!allowed_.empty()) {
      const std::string key = frames[6].to_string();
      if (!allowed_.count(key)) {
        status = "400";
        text = "key not allowed";
        spdlog::warn("refused a worker from {}: its public key {} is not in {}", address,
                     Z85Encode(key), options_.curve_public_keys_dir);
      }
    }
    const std::string reply[6] = {version, request_id, status, text, "", ""};
    for (int i = 0; i < 6; ++i) {
      zap_->send(zmq::buffer(reply[i]), i < 5 ? zmq::send_flags::sndmore : zmq::send_flags::none);
    }
  }

  void HandleMonitor() {
    uint16_t event = 0;
    uint32_t value = 0;
    std::string address;
    while (monitor_->Read(&event, &value, &address)) {
      // Refusals by ZAP are logged by HandleZap; the others mean a peer with a wrong server
      // key (CURVE), a peer with another security mechanism, or one that does not speak ZMTP.
      if (event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) continue;
      // ZeroMQ retries a failed connection every 100 ms: the first few per peer address and
      // kind, then every 100th.
      const int64_t n = ++handshake_failures_[address + "/" + std::to_string(value)];
      if (n > 3 && n % 100 != 0) continue;
      // A peer that hangs up during the handshake (value = errno) is noise without CURVE.
      const auto level = event == ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL && !zap_
                             ? spdlog::level::debug
                             : spdlog::level::warn;
      std::string why;
      if (value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH) {
        why = zap_ ? ": the worker does not use CURVE (--curve-server-key)"
                   : ": the worker uses CURVE, this coordinator does not";
      } else if (zap_) {
        why = ": a worker with a wrong --curve-server-key?";
      }
      spdlog::log(level, "connection from {}: {} (code {:#x}){}{}", address, EventName(event),
                  value, why, n > 3 ? fmt::format(" ({} times)", n) : "");
    }
  }

  std::map<std::string, int64_t> handshake_failures_;
  ZmqServerOptions options_;
  zmq::context_t context_;
  zmq::socket_t router_;
  std::unique_ptr<zmq::socket_t> zap_;
  std::unique_ptr<Monitor> monitor_;
  std::set<std::string> allowed_;  // binary public keys; empty: any
  std::string endpoint_;
};

// ---- Client

class ZmqClient : public ClientTransport {
 public:
  explicit ZmqClient(const ZmqClientOptions& options)
      : context_(1), dealer_(context_, zmq::socket_type::dealer) {
    dealer_.set(zmq::sockopt::linger, 200);  // reconnecting must not wait long
    dealer_.set(zmq::sockopt::maxmsgsize,
                static_cast<int64_t>(std::min<uint64_t>(2 * options.max_message_bytes, INT64_MAX)));
    if (!options.curve_server_key_file.empty()) {
      RequireCurve("--curve-server-key");
      const CurveKeyPair server = ReadCurveKeyFile(options.curve_server_key_file, false);
      const CurveKeyPair own = options.curve_secret_key_file.empty()
                                   ? GenerateCurveKeyPair()
                                   : ReadCurveKeyFile(options.curve_secret_key_file, true);
      SetBinaryOption(dealer_, ZMQ_CURVE_SERVERKEY, Z85Decode(server.public_key));
      SetBinaryOption(dealer_, ZMQ_CURVE_PUBLICKEY, Z85Decode(own.public_key));
      SetBinaryOption(dealer_, ZMQ_CURVE_SECRETKEY, Z85Decode(own.secret_key));
    } else if (!options.curve_secret_key_file.empty()) {
      throw InputError(
          "--curve-secret-key needs --curve-server-key (the coordinator's public key)");
    }
    monitor_ =
        std::make_unique<Monitor>(context_, dealer_, "dealer", ZMQ_EVENT_HANDSHAKE_FAILED_AUTH);
    try {
      dealer_.connect(options.connect);
    } catch (const zmq::error_t& e) {
      throw InputError("--connect " + options.connect + ": " + e.what());
    }
  }

  bool Receive(double timeout_s, std::string* payload) override {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      zmq_pollitem_t items[2] = {{dealer_.handle(), 0, ZMQ_POLLIN, 0},
                                 {monitor_->socket().handle(), 0, ZMQ_POLLIN, 0}};
      const double left =
          std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
      Poll(items, 2, std::max(0.0, left));
      if (items[1].revents & ZMQ_POLLIN) {
        uint16_t event = 0;
        uint32_t value = 0;
        std::string address;
        while (monitor_->Read(&event, &value, &address)) {
          if (event == ZMQ_EVENT_HANDSHAKE_FAILED_AUTH) {
            auth_failure_ = "the coordinator at " + address +
                            " refused this worker's CURVE key (ZAP status " +
                            std::to_string(value) + ")";
          }
        }
        if (!auth_failure_.empty()) return false;
      }
      if (items[0].revents & ZMQ_POLLIN) {
        std::vector<zmq::message_t> frames;
        if (ReceiveFrames(dealer_, &frames) && !frames.empty()) {
          // A server message has exactly one frame; anything else is passed on as a
          // frame the protocol layer rejects (empty payload).
          *payload = frames.size() == 1 ? frames[0].to_string() : std::string();
          return true;
        }
      }
      if (std::chrono::steady_clock::now() >= deadline) return false;
    }
  }

  void Send(const std::string& payload) override {
    try {
      dealer_.send(zmq::buffer(payload), zmq::send_flags::dontwait);
    } catch (const zmq::error_t& e) {
      spdlog::warn("could not send {} bytes to the coordinator: {}", payload.size(), e.what());
    }
  }

  std::string AuthFailure() const override { return auth_failure_; }

 private:
  zmq::context_t context_;
  zmq::socket_t dealer_;
  std::unique_ptr<Monitor> monitor_;
  std::string auth_failure_;
};

}  // namespace

bool CurveAvailable() { return zmq_has("curve") != 0; }

void RequireCurve(const std::string& option) {
  if (!CurveAvailable()) {
    int major = 0, minor = 0, patch = 0;
    zmq_version(&major, &minor, &patch);
    throw InputError(option + ": this libzmq (" + std::to_string(major) + "." +
                     std::to_string(minor) + "." + std::to_string(patch) +
                     ") was built without CURVE security (zmq_has(\"curve\") is false); "
                     "install a libzmq built with libsodium (Debian's libzmq5 is)");
  }
}

CurveKeyPair GenerateCurveKeyPair() {
  RequireCurve("keygen");
  char public_key[41], secret_key[41];
  if (zmq_curve_keypair(public_key, secret_key) != 0) {
    throw InternalError(std::string("zmq_curve_keypair: ") + zmq_strerror(zmq_errno()));
  }
  return CurveKeyPair{std::string(public_key, 40), std::string(secret_key, 40)};
}

void WriteCurveKeyFiles(const CurveKeyPair& keys, const std::string& base, bool overwrite) {
  const std::string public_path = base + ".key", secret_path = base + ".key_secret";
  for (const std::string& path : {public_path, secret_path}) {
    if (!overwrite && fs::exists(path)) {
      throw InputError(path + ": exists already (pass --force to replace it)");
    }
  }
  WriteFileAtomically(
      public_path,
      [&](std::ostream& out) {
        out << "# manisweep CURVE public key (ZeroMQ Z85). Give it to the other side:\n"
               "# a coordinator's to its workers (--curve-server-key), a worker's into the\n"
               "# coordinator's --curve-public-keys directory.\n"
            << "public-key = \"" << keys.public_key << "\"\n";
      },
      false);
  // The secret file is created private before anything is written into it.
  const fs::path temp = TempPathFor(secret_path);
  {
    const mode_t old_mask = ::umask(077);
    std::ofstream out(temp);
    ::umask(old_mask);
    out << "# manisweep CURVE key pair (ZeroMQ Z85). SECRET: keep it on this machine.\n"
        << "public-key = \"" << keys.public_key << "\"\n"
        << "secret-key = \"" << keys.secret_key << "\"\n";
    out.close();
    if (!out) throw InputError(temp.string() + ": cannot write");
  }
  fs::permissions(temp, fs::perms::owner_read | fs::perms::owner_write);
  CommitTempFile(temp, secret_path);
}

CurveKeyPair ReadCurveKeyFile(const std::string& path, bool need_secret) {
  TextReader reader(path, 1 << 16);
  CurveKeyPair keys;
  std::string_view line;
  while (reader.NextDataLine(&line)) {
    const size_t eq = line.find('=');
    if (eq == std::string_view::npos) reader.Fail("expected 'name = \"value\"'");
    const std::string name(Trim(line.substr(0, eq)));
    std::string value(Trim(line.substr(eq + 1)));
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"') {
      value = value.substr(1, value.size() - 2);
    }
    if (name != "public-key" && name != "secret-key") {
      reader.Fail("unknown field '" + name + "' (expected public-key or secret-key)");
    }
    if (Z85Decode(value).empty()) {
      reader.Fail(name + ": not a 40-character Z85 CURVE key");
    }
    (name == "public-key" ? keys.public_key : keys.secret_key) = value;
  }
  if (keys.public_key.empty()) throw InputError(path + ": no public-key");
  if (need_secret) {
    if (keys.secret_key.empty()) {
      throw InputError(path + ": no secret-key (this option needs the *.key_secret file)");
    }
    char derived[41];
    if (zmq_curve_public(derived, keys.secret_key.c_str()) != 0 ||
        keys.public_key != std::string(derived, 40)) {
      throw InputError(path + ": secret-key does not belong to public-key");
    }
  }
  return keys;
}

std::vector<CurveKeyPair> ReadPublicKeyDirectory(const std::string& directory) {
  RequireDirectory(directory, "directory of allowed public keys");
  std::vector<std::string> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(directory)) {
    if (entry.is_regular_file() && entry.path().extension() == ".key") {
      files.push_back(entry.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  std::vector<CurveKeyPair> keys;
  for (const std::string& file : files) keys.push_back(ReadCurveKeyFile(file, false));
  return keys;
}

bool IsLocalOnlyEndpoint(const std::string& endpoint) {
  if (endpoint.rfind("ipc://", 0) == 0 || endpoint.rfind("inproc://", 0) == 0) return true;
  if (endpoint.rfind("tcp://", 0) != 0) return false;
  const std::string address = endpoint.substr(6);
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos) return false;
  std::string host = address.substr(0, colon);
  // ZeroMQ's "tcp://interface;remote" form: only the part that is bound matters.
  if (const size_t semicolon = host.find(';'); semicolon != std::string::npos) {
    host = host.substr(0, semicolon);
  }
  if (host == "localhost" || host == "[::1]" || host == "::1") return true;
  // 127.0.0.0/8, written as four decimal numbers.
  int a = -1, b = -1, c = -1, d = -1;
  char end = 0;
  return std::sscanf(host.c_str(), "%d.%d.%d.%d%c", &a, &b, &c, &d, &end) == 4 && a == 127 &&
         b >= 0 && b <= 255 && c >= 0 && c <= 255 && d >= 0 && d <= 255;
}

std::unique_ptr<ServerTransport> MakeZmqServer(const ZmqServerOptions& options) {
  return std::make_unique<ZmqServer>(options);
}

std::unique_ptr<ClientTransport> MakeZmqClient(const ZmqClientOptions& options) {
  return std::make_unique<ZmqClient>(options);
}

}  // namespace ms
