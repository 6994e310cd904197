// File helpers that keep the error contract: every failure names the file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace ms {

// Reads a whole file. Throws InputError if it is missing, unreadable or larger than max_bytes
// (a guard against unbounded allocation on garbage input).
std::string ReadFileToString(const std::filesystem::path& path,
                             uint64_t max_bytes = uint64_t{1} << 31);

// Throws InputError("<path>: <what> not found") unless the path is an existing regular file.
void RequireFile(const std::filesystem::path& path, const std::string& what = "file");
void RequireDirectory(const std::filesystem::path& path, const std::string& what = "directory");

// Writes to "<path>.tmp-<pid>" and renames onto `path` only in Commit(), so a crash or an
// exception never leaves a partial file that looks complete. Creates parent directories.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path, bool binary = true);
  ~AtomicFileWriter();  // Removes the temporary file unless committed.
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  std::ostream& stream() { return stream_; }
  const std::filesystem::path& temp_path() const { return temp_path_; }
  // Flushes, checks the stream, renames. Throws InputError naming the path on failure.
  void Commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  std::ofstream stream_;
  bool committed_ = false;
};

// Convenience: AtomicFileWriter + a body that writes into the stream.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write, bool binary = true);

// Temporary path beside `path` for writers that need a file name (HDF5, OpenCV), and the rename.
std::filesystem::path TempPathFor(const std::filesystem::path& path);
void CommitTempFile(const std::filesystem::path& temp_path, const std::filesystem::path& path);

}  // namespace ms
