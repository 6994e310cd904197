#include "base/binary_reader.h"

#include <cmath>

#include "base/error.h"

namespace ms {

void BinaryReader::Fail(const std::string& message) const {
  throw InputError(name_ + ": byte " + std::to_string(pos_) + ": " + message);
}

void BinaryReader::Need(size_t bytes, const char* field) const {
  if (bytes > size_ - pos_) {
    Fail(std::string(field) + ": truncated (needs " + std::to_string(bytes) + " bytes, " +
         std::to_string(size_ - pos_) + " left)");
  }
}

double BinaryReader::ReadFiniteDouble(const char* field) {
  const double v = Read<double>(field);
  if (!std::isfinite(v)) Fail(std::string(field) + ": value is not finite");
  return v;
}

float BinaryReader::ReadFiniteFloat(const char* field) {
  const float v = Read<float>(field);
  if (!std::isfinite(v)) Fail(std::string(field) + ": value is not finite");
  return v;
}

std::string BinaryReader::ReadCString(const char* field, size_t max_length) {
  const size_t start = pos_;
  const size_t limit = std::min(size_, pos_ + max_length + 1);
  for (size_t i = start; i < limit; ++i) {
    if (data_[i] == '\0') {
      pos_ = i + 1;
      return std::string(data_ + start, i - start);
    }
  }
  Fail(std::string(field) + ": unterminated string (no NUL within " + std::to_string(max_length) +
       " bytes)");
}

void BinaryReader::Skip(size_t bytes, const char* field) {
  Need(bytes, field);
  pos_ += bytes;
}

void BinaryReader::CheckCount(uint64_t count, size_t min_bytes_each, const char* field) const {
  if (min_bytes_each == 0) min_bytes_each = 1;
  if (count > remaining() / min_bytes_each) {
    Fail(std::string(field) + ": count " + std::to_string(count) + " needs at least " +
         std::to_string(count) + " x " + std::to_string(min_bytes_each) + " bytes but only " +
         std::to_string(remaining()) + " remain");
  }
}

}  // namespace ms
