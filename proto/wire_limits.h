// Size limits of protocol messages. Plain C++ (no protobuf), so option structs can hold them.
#pragma once

#include <cstdint>

namespace ms {

struct WireLimits {
  // Largest message accepted or sent, in bytes. A job carries the mesh the camera sees (24 bytes
  // per vertex, 12 per face: a 1M-face visible mesh is ~18 MiB); a result is small.
  uint64_t max_message_bytes = uint64_t{64} << 20;
  // Image files travel in pieces of at most this many bytes (ImageRequest/ImageResponse).
  uint64_t image_chunk_bytes = uint64_t{4} << 20;
  void Check() const;  // throws InputError naming the field
};

// The limits for a largest message of `max_message_mb` MiB (--max-message-mb): image chunks at
// most half of it.
WireLimits WireLimitsFromMiB(double max_message_mb);

}  // namespace ms
