// Bounds-checked little-endian reading of a byte buffer. Every failure names the source and
// the byte offset; counts read from the data are checked against the bytes left before any
// allocation, so garbage input cannot ask for unbounded memory.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

namespace ms {

class BinaryReader {
 public:
  BinaryReader(std::string name, const char* data, size_t size)
      : name_(std::move(name)), data_(data), size_(size) {}

  template <typename T>
  T Read(const char* field) {
    static_assert(std::is_trivially_copyable_v<T>);
    Need(sizeof(T), field);
    T value;
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  // Reads a finite double/float (rejects NaN and infinity).
  double ReadFiniteDouble(const char* field);
  float ReadFiniteFloat(const char* field);

  // NUL-terminated string of at most max_length bytes.
  std::string ReadCString(const char* field, size_t max_length = 4096);
  void Skip(size_t bytes, const char* field);

  // Throws unless count * min_bytes_each bytes remain: call before reserving `count` items.
  void CheckCount(uint64_t count, size_t min_bytes_each, const char* field) const;

  size_t position() const { return pos_; }
  size_t remaining() const { return size_ - pos_; }
  bool AtEnd() const { return pos_ == size_; }
  const std::string& name() const { return name_; }
  [[noreturn]] void Fail(const std::string& message) const;

 private:
  void Need(size_t bytes, const char* field) const;
  std::string name_;
  const char* data_;
  size_t size_;
  size_t pos_ = 0;
};

}  // namespace ms
