#include "proto/wire.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "base/check.h"
#include "base/error.h"

namespace ms {
namespace {

void PutU32(uint32_t v, char* out) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<char>((v >> (8 * i)) & 0xff);
}
void PutF64(double d, char* out) {
  uint64_t v;
  std::memcpy(&v, &d, 8);
  for (int i = 0; i < 8; ++i) out[i] = static_cast<char>((v >> (8 * i)) & 0xff);
}
uint32_t GetU32(const char* in) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(in[i]);
  return v;
}
double GetF64(const char* in) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(in[i]);
  double d;
  std::memcpy(&d, &v, 8);
  return d;
}

}  // namespace

void WireLimits::Check() const {
  if (max_message_bytes < (uint64_t{64} << 10)) {
    throw InputError("max_message_bytes: must be at least 64 KiB, got " +
                     std::to_string(max_message_bytes));
  }
  if (max_message_bytes > (uint64_t{1} << 31)) {
    throw InputError("max_message_bytes: at most 2 GiB (protobuf's limit), got " +
                     std::to_string(max_message_bytes));
  }
  if (image_chunk_bytes < 1024 || image_chunk_bytes + 4096 > max_message_bytes) {
    throw InputError("image_chunk_bytes: must be in [1 KiB, max_message_bytes - 4 KiB], got " +
                     std::to_string(image_chunk_bytes));
  }
}

WireLimits WireLimitsFromMiB(double max_message_mb) {
  WireLimits limits;
  limits.max_message_bytes = static_cast<uint64_t>(std::llround(max_message_mb * 1048576));
  limits.image_chunk_bytes =
      std::min<uint64_t>(limits.image_chunk_bytes, limits.max_message_bytes / 2);
  return limits;
}

const char* DecodeStatusName(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kOversized:
      return "oversized";
    case DecodeStatus::kMalformed:
      return "malformed";
    case DecodeStatus::kWrongVersion:
      return "wrong protocol version";
    case DecodeStatus::kNoBody:
      return "no body";
  }
  return "?";
}

DecodeStatus DecodeEnvelope(const void* data, size_t size, const WireLimits& limits,
                            wire::Envelope* envelope, std::string* problem) {
  envelope->Clear();
  if (size > limits.max_message_bytes) {
    *problem = std::to_string(size) + " bytes, over the limit of " +
               std::to_string(limits.max_message_bytes);
    return DecodeStatus::kOversized;
  }
  if (!envelope->ParseFromArray(data, static_cast<int>(size))) {
    envelope->Clear();
    *problem = std::to_string(size) + " bytes that are not a manisweep protocol envelope";
    return DecodeStatus::kMalformed;
  }
  if (envelope->protocol_version() != kProtocolVersion) {
    *problem = "protocol version " + std::to_string(envelope->protocol_version()) +
               " (this side speaks version " + std::to_string(kProtocolVersion) + ")";
    return DecodeStatus::kWrongVersion;
  }
  if (envelope->body_case() == wire::Envelope::BODY_NOT_SET) {
    *problem = "an envelope without a known body";
    return DecodeStatus::kNoBody;
  }
  problem->clear();
  return DecodeStatus::kOk;
}

wire::Envelope EnvelopeStamper::New() {
  wire::Envelope envelope;
  envelope.set_protocol_version(kProtocolVersion);
  envelope.set_message_id(next_id_++);
  envelope.set_sender(sender_);
  return envelope;
}

std::string Serialize(const google::protobuf::MessageLite& message) {
  // The messages have no map fields, so the default serialization is already deterministic.
  std::string bytes;
  MS_CHECK(message.SerializeToString(&bytes)) << "cannot serialize a " << message.GetTypeName();
  return bytes;
}

const char* BodyName(const wire::Envelope& envelope) {
  switch (envelope.body_case()) {
    case wire::Envelope::kReady:
      return "ready";
    case wire::Envelope::kHeartbeat:
      return "heartbeat";
    case wire::Envelope::kJob:
      return "job";
    case wire::Envelope::kResult:
      return "result";
    case wire::Envelope::kError:
      return "error";
    case wire::Envelope::kImageRequest:
      return "image request";
    case wire::Envelope::kImageResponse:
      return "image response";
    case wire::Envelope::kShutdown:
      return "shutdown";
    case wire::Envelope::BODY_NOT_SET:
      return "none";
  }
  return "?";
}

void PackMesh(const Mesh& mesh, wire::PackedMesh* packed) {
  MS_CHECK(mesh.vertices.size() <= std::numeric_limits<uint32_t>::max() &&
           mesh.faces.size() <= std::numeric_limits<uint32_t>::max());
  packed->set_num_vertices(static_cast<uint32_t>(mesh.vertices.size()));
  packed->set_num_faces(static_cast<uint32_t>(mesh.faces.size()));
  std::string* vertices = packed->mutable_vertices();
  vertices->resize(24 * mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) PutF64(mesh.vertices[i][k], &(*vertices)[24 * i + 8 * k]);
  }
  std::string* faces = packed->mutable_faces();
  faces->resize(12 * mesh.faces.size());
  for (size_t i = 0; i < mesh.faces.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      PutU32(static_cast<uint32_t>(mesh.faces[i][k]), &(*faces)[12 * i + 4 * k]);
    }
  }
}

Mesh UnpackMesh(const wire::PackedMesh& packed, const std::string& what) {
  const uint64_t nv = packed.num_vertices(), nf = packed.num_faces();
  if (packed.vertices().size() != 24 * nv) {
    throw InputError(what + ": mesh: " + std::to_string(nv) + " vertices need " +
                     std::to_string(24 * nv) + " bytes, got " +
                     std::to_string(packed.vertices().size()));
  }
  if (packed.faces().size() != 12 * nf) {
    throw InputError(what + ": mesh: " + std::to_string(nf) + " faces need " +
                     std::to_string(12 * nf) + " bytes, got " +
                     std::to_string(packed.faces().size()));
  }
  if (nv > static_cast<uint64_t>(std::numeric_limits<int32_t>::max())) {
    throw InputError(what + ": mesh: too many vertices (" + std::to_string(nv) + ")");
  }
  Mesh mesh;
  mesh.vertices.resize(nv);
  const char* v = packed.vertices().data();
  for (uint64_t i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double x = GetF64(v + 24 * i + 8 * k);
      if (!std::isfinite(x)) {
        throw InputError(what + ": mesh: vertex " + std::to_string(i) + " is not finite");
      }
      mesh.vertices[i][k] = x;
    }
  }
  mesh.faces.resize(nf);
  const char* f = packed.faces().data();
  for (uint64_t i = 0; i < nf; ++i) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t index = GetU32(f + 12 * i + 4 * k);
      if (index >= nv) {
        throw InputError(what + ": mesh: face " + std::to_string(i) + " refers to vertex " +
                         std::to_string(index) + " of " + std::to_string(nv));
      }
      mesh.faces[i][k] = static_cast<int32_t>(index);
    }
  }
  return mesh;
}

void ViewToWire(int32_t id, const View& view, wire::JobCamera* camera) {
  camera->set_id(id);
  camera->set_name(view.name);
  wire::Intrinsics* k = camera->mutable_intrinsics();
  const Intrinsics& in = view.intrinsics;
  k->set_width(in.width);
  k->set_height(in.height);
  k->set_fx(in.fx);
  k->set_fy(in.fy);
  k->set_cx(in.cx);
  k->set_cy(in.cy);
  k->set_k1(in.k1);
  k->set_k2(in.k2);
  k->set_p1(in.p1);
  k->set_p2(in.p2);
  k->set_k3(in.k3);
  camera->clear_rotation();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) camera->add_rotation(view.R(r, c));
  }
  camera->clear_translation();
  for (int r = 0; r < 3; ++r) camera->add_translation(view.t[r]);
}

View ViewFromWire(const wire::JobCamera& camera, const std::string& what) {
  const std::string name = what + ": camera " + std::to_string(camera.id());
  if (camera.rotation_size() != 9 || camera.translation_size() != 3) {
    throw InputError(name + ": pose needs 9 rotation and 3 translation values, got " +
                     std::to_string(camera.rotation_size()) + " and " +
                     std::to_string(camera.translation_size()));
  }
  View view;
  view.name = camera.name();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) view.R(r, c) = camera.rotation(3 * r + c);
    view.t[r] = camera.translation(r);
  }
  const wire::Intrinsics& k = camera.intrinsics();
  Intrinsics& in = view.intrinsics;
  in.width = k.width();
  in.height = k.height();
  in.fx = k.fx();
  in.fy = k.fy();
  in.cx = k.cx();
  in.cy = k.cy();
  in.k1 = k.k1();
  in.k2 = k.k2();
  in.p1 = k.p1();
  in.p2 = k.p2();
  in.k3 = k.k3();
  const double values[] = {in.fx, in.fy, in.cx, in.cy, in.k1, in.k2, in.p1, in.p2, in.k3};
  for (double x : values) {
    if (!std::isfinite(x)) throw InputError(name + ": intrinsics are not finite");
  }
  if (!view.R.allFinite() || !view.t.allFinite()) {
    throw InputError(name + ": pose is not finite");
  }
  if (!IsRotation(view.R, 1e-6)) throw InputError(name + ": R is not a rotation");
  if (in.width <= 0 || in.height <= 0 || in.width > 65536 || in.height > 65536) {
    throw InputError(name + ": image size " + std::to_string(in.width) + "x" +
                     std::to_string(in.height) + " out of range");
  }
  if (!(in.fx > 0 && in.fy > 0)) throw InputError(name + ": focal lengths must be positive");
  return view;
}

}  // namespace ms
