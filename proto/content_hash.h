// Content hashes of image files, so a worker can tell that its copy of a file is the
// coordinator's and fetch and cache images by hash.
//
// The hash is XXH64 (Yann Collet's xxHash, 64-bit variant, seed 0), implemented here in a few
// lines because the project uses Debian packages only and OpenSSL is not among them. It is a
// fast checksum against stale or different copies, not a cryptographic hash: it does not
// protect against a peer that forges files on purpose (use CURVE for trust between processes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace ms {

// Incremental XXH64: Update() any number of times, Digest() at any point.
class Xxh64 {
 public:
  explicit Xxh64(uint64_t seed = 0);
  void Update(const void* data, size_t size);
  void Update(std::string_view data) { Update(data.data(), data.size()); }
  uint64_t Digest() const;

 private:
  uint64_t v_[4];
  uint64_t seed_;
  uint64_t total_ = 0;
  unsigned char buffer_[32];
  size_t buffered_ = 0;
};

uint64_t HashBytes(const void* data, size_t size, uint64_t seed = 0);
inline uint64_t HashBytes(std::string_view data) { return HashBytes(data.data(), data.size()); }

struct FileHash {
  uint64_t hash = 0;
  uint64_t size = 0;
};
// Hashes a file by streaming it. Throws InputError naming the file if it cannot be read.
FileHash HashFile(const std::string& path);

// 16 lower-case hex digits, the form used in file names and logs.
std::string HashHex(uint64_t hash);

}  // namespace ms
