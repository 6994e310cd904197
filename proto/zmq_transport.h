// The ZeroMQ transports: the coordinator binds a ROUTER, workers connect a DEALER
// (proto/PROTOCOL.md). Optional CURVE security: encryption plus an allow-list of worker public
// keys, enforced by a ZAP handler in the coordinator that logs every refusal. No ZeroMQ type
// appears in this header.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "proto/transport.h"

namespace ms {

// ---- CURVE keys

// True if this libzmq was built with CURVE (libsodium); Debian's is.
bool CurveAvailable();
// Throws InputError with a clear message if CURVE is not available ("--<option> needs ...").
void RequireCurve(const std::string& option);

// A CURVE key pair in ZeroMQ's Z85 text form (40 characters each).
struct CurveKeyPair {
  std::string public_key;
  std::string secret_key;  // empty for a public-key file
};
CurveKeyPair GenerateCurveKeyPair();
// Writes "<base>.key" (public key only: give it to the other side) and "<base>.key_secret"
// (both keys, mode 0600), atomically. Throws InputError if either exists and !overwrite.
void WriteCurveKeyFiles(const CurveKeyPair& keys, const std::string& base, bool overwrite);
// Reads a key file (`public-key = "..."`, `secret-key = "..."`, '#' comments). Throws
// InputError naming the file and line for a malformed file, a key that is not valid Z85, a
// missing secret key when need_secret, or a secret key that does not match the public key.
CurveKeyPair ReadCurveKeyFile(const std::string& path, bool need_secret);
// Every "*.key" file of a directory, sorted by name (public keys of allowed workers).
std::vector<CurveKeyPair> ReadPublicKeyDirectory(const std::string& directory);

// ---- Transports

struct ZmqServerOptions {
  std::string bind;  // e.g. "tcp://*:5555"; "tcp://127.0.0.1:*" picks a free port
  // Messages larger than this are logged and dropped by the protocol layer; ZeroMQ itself
  // drops the connection of a peer whose message exceeds twice this (memory protection).
  uint64_t max_message_bytes = uint64_t{64} << 20;
  std::string curve_secret_key_file;  // non-empty: CURVE server with this key pair
  std::string curve_public_keys_dir;  // non-empty: only workers with a key in here
};
// Binds and returns the server. Throws InputError naming the address if it cannot bind, or for
// bad key files.
std::unique_ptr<ServerTransport> MakeZmqServer(const ZmqServerOptions& options);

// True if a bind address can only be reached from this machine: tcp:// on 127.0.0.0/8,
// localhost or [::1], and ipc:// or inproc://. "tcp://*:P", a host name or any other address is
// reachable from the network.
bool IsLocalOnlyEndpoint(const std::string& endpoint);

struct ZmqClientOptions {
  std::string connect;  // e.g. "tcp://node01:5555"
  uint64_t max_message_bytes = uint64_t{64} << 20;
  std::string curve_server_key_file;  // non-empty: CURVE client of a server with this public key
  std::string curve_secret_key_file;  // this worker's key pair (generated per process if empty)
};
std::unique_ptr<ClientTransport> MakeZmqClient(const ZmqClientOptions& options);

}  // namespace ms
