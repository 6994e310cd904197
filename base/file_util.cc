#include "base/file_util.h"

#include <unistd.h>

#include <system_error>

#include "base/error.h"

namespace fs = std::filesystem;

namespace ms {

std::string ReadFileToString(const fs::path& path, uint64_t max_bytes) {
  RequireFile(path);
  std::error_code ec;
  const uint64_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path.string() + ": cannot read size: " + ec.message());
  if (size > max_bytes) {
    throw InputError(path.string() + ": file is " + std::to_string(size) +
                     " bytes, larger than the limit of " + std::to_string(max_bytes));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open for reading");
  std::string data(size, '\0');
  in.read(data.data(), static_cast<std::streamsize>(size));
  if (static_cast<uint64_t>(in.gcount()) != size) {
    throw InputError(path.string() + ": read failed");
  }
  return data;
}

void RequireFile(const fs::path& path, const std::string& what) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path.string() + ": " + what + " not found");
  if (!fs::is_regular_file(path, ec)) {
    throw InputError(path.string() + ": " + what + " is not a regular file");
  }
}

void RequireDirectory(const fs::path& path, const std::string& what) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path.string() + ": " + what + " not found");
  if (!fs::is_directory(path, ec)) throw InputError(path.string() + ": not a " + what);
}

fs::path TempPathFor(const fs::path& path) {
  return fs::path(path.string() + ".tmp-" + std::to_string(::getpid()));
}

void CommitTempFile(const fs::path& temp_path, const fs::path& path) {
  std::error_code ec;
  fs::rename(temp_path, path, ec);
  if (ec) {
    fs::remove(temp_path, ec);
    throw InputError(path.string() + ": cannot move finished file into place: " + ec.message());
  }
}

AtomicFileWriter::AtomicFileWriter(fs::path path, bool binary)
    : path_(std::move(path)), temp_path_(TempPathFor(path_)) {
  std::error_code ec;
  if (path_.has_parent_path()) fs::create_directories(path_.parent_path(), ec);
  stream_.open(temp_path_, binary ? std::ios::binary | std::ios::out : std::ios::out);
  if (!stream_) throw InputError(path_.string() + ": cannot open for writing");
}

AtomicFileWriter::~AtomicFileWriter() {
  if (!committed_) {
    stream_.close();
    std::error_code ec;
    fs::remove(temp_path_, ec);
  }
}

void AtomicFileWriter::Commit() {
  stream_.flush();
  if (!stream_) throw InputError(path_.string() + ": write failed (disk full?)");
  stream_.close();
  if (stream_.fail()) throw InputError(path_.string() + ": write failed on close");
  CommitTempFile(temp_path_, path_);
  committed_ = true;
}

void WriteFileAtomically(const fs::path& path, const std::function<void(std::ostream&)>& write,
                         bool binary) {
  AtomicFileWriter writer(path, binary);
  write(writer.stream());
  writer.Commit();
}

}  // namespace ms
