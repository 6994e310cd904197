// The wire format around proto/manisweep.proto: one versioned Envelope per ZeroMQ frame, checked
// before anything trusts it, and the packing of meshes and cameras into jobs. Shared by the
// coordinator and the worker (proto/PROTOCOL.md describes the conversation).
#pragma once

#include <cstdint>
#include <string>

#include "mesh/mesh.h"
#include "proto/manisweep.pb.h"
#include "proto/wire_limits.h"
#include "scene/camera.h"

namespace ms {

// The version both sides put in every envelope and require in every envelope they read.
// 2: refinement jobs (Job.refine, Result.gradient).
constexpr uint32_t kProtocolVersion = 2;

enum class DecodeStatus {
  kOk,
  kOversized,     // larger than max_message_bytes: not even parsed
  kMalformed,     // not a valid Envelope
  kWrongVersion,  // parsed, but protocol_version != kProtocolVersion (envelope filled)
  kNoBody,        // parsed, right version, but no body set (e.g. a newer body type)
};
const char* DecodeStatusName(DecodeStatus status);

// Parses one frame into *envelope. Never throws on bad bytes; *problem says what was wrong
// in one line (for the log).
DecodeStatus DecodeEnvelope(const void* data, size_t size, const WireLimits& limits,
                            wire::Envelope* envelope, std::string* problem);

// Stamps envelopes of one sender: version, sender, increasing message ids.
class EnvelopeStamper {
 public:
  explicit EnvelopeStamper(std::string sender) : sender_(std::move(sender)) {}
  wire::Envelope New();
  const std::string& sender() const { return sender_; }

 private:
  std::string sender_;
  uint64_t next_id_ = 1;
};

// Serializes (deterministically: equal messages give equal bytes).
std::string Serialize(const google::protobuf::MessageLite& message);

// "ready", "heartbeat", "job", ..., "none".
const char* BodyName(const wire::Envelope& envelope);

// ---- Meshes: little-endian float64 vertices and int32 faces.
void PackMesh(const Mesh& mesh, wire::PackedMesh* packed);
// Throws InputError naming `what` if sizes disagree, an index is out of range or a coordinate
// is not finite. Counts are checked against the byte sizes before allocating.
Mesh UnpackMesh(const wire::PackedMesh& packed, const std::string& what);

// ---- Cameras (without the image reference).
void ViewToWire(int32_t id, const View& view, wire::JobCamera* camera);
// Throws InputError naming `what` for a wrong number of pose values, non-finite values, a
// non-rotation or a bad image size / focal length.
View ViewFromWire(const wire::JobCamera& camera, const std::string& what);

// Job ids: (iteration << 32) | camera. Unique within a run, equal across restarts of it.
inline uint64_t MakeJobId(uint32_t iteration, uint32_t camera) {
  return (uint64_t{iteration} << 32) | camera;
}
inline uint32_t JobIdIteration(uint64_t job_id) { return static_cast<uint32_t>(job_id >> 32); }
inline uint32_t JobIdCamera(uint64_t job_id) { return static_cast<uint32_t>(job_id & 0xffffffffu); }
// "3/12": iteration 3, camera 12 (for logs).
inline std::string JobName(uint64_t job_id) {
  return std::to_string(JobIdIteration(job_id)) + "/" + std::to_string(JobIdCamera(job_id));
}

}  // namespace ms
