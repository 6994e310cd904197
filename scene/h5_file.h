// A small typed layer over HDF5, the project's canonical store (scene, per-iteration statistics,
// checkpoints). No HDF5 type appears here; the library stays in h5_file.cc.
//
// - Objects are named by '/'-separated paths ("/views/fx"; a leading '/' is optional).
//   Writing a dataset creates its parent groups.
// - Arrays are row-major with an explicit shape (outermost extent first, as numpy shows it).
// - Every failure (missing file, not HDF5, truncated or corrupt file, missing object, wrong type
//   or shape, disk full) throws InputError naming the file and the object path. HDF5's own
//   printing of error stacks to stderr is switched off.
// - Reads check the stored shape against what the caller expects, and its size against the file
//   (and H5FileOptions::max_read_bytes), before allocating: a corrupt header claiming 2^40
//   elements is an error, not an allocation.
// - Not thread-safe: one H5File per thread, never shared. HDF5 locks files: a file open for
//   writing cannot be opened by another process at the same time.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

namespace ms {

enum class H5Type { kFloat64, kFloat32, kInt32, kInt64, kUInt8, kString };
// "float64", "float32", "int32", "int64", "uint8", "string".
std::string H5TypeName(H5Type type);

// Dataset extents, outermost first. A dataset has rank 1 to kH5MaxRank.
using H5Shape = std::vector<uint64_t>;
constexpr int kH5MaxRank = 4;
// Matches any extent in an expected shape: Read<double>("/p", {kH5Any, 3}).
constexpr uint64_t kH5Any = std::numeric_limits<uint64_t>::max();
// "(3, 4)" / "(any, 3)".
std::string H5ShapeString(const H5Shape& shape);

struct H5DatasetInfo {
  H5Type type = H5Type::kFloat64;
  H5Shape shape;
  uint64_t num_elements = 0;
  bool chunked = false;
  bool compressed = false;  // any filter (deflate) in the pipeline
  bool extendible = false;  // an unlimited extent (table columns)
};

struct H5FileOptions {
  // Datasets of at least this many bytes are chunked and compressed with deflate (when the
  // HDF5 build has it; Debian's does). Smaller ones are stored contiguously.
  uint64_t compress_min_bytes = uint64_t{64} << 10;
  int deflate_level = 4;  // 1 (fast) .. 9 (small); 0 chunks large datasets without compressing
  bool shuffle = true;    // byte shuffle before deflate: much better ratios on doubles
  // Target bytes per chunk; HDF5's default chunk cache holds 1 MiB per dataset.
  uint64_t chunk_bytes = uint64_t{256} << 10;
  uint64_t table_chunk_rows = 256;  // rows per chunk of an appendable table column
  // Upper bound on one dataset read into memory, on top of the check against the file's size.
  uint64_t max_read_bytes = uint64_t{16} << 30;

  void Check() const;  // throws InputError naming the field
};

// Element types the array functions accept.
template <typename T>
inline constexpr bool kIsH5Element =
    std::is_same_v<T, double> || std::is_same_v<T, float> || std::is_same_v<T, int32_t> ||
    std::is_same_v<T, int64_t> || std::is_same_v<T, uint8_t> || std::is_same_v<T, std::string>;

// A column of an appendable table, and one cell value.
struct H5Column {
  std::string name;  // [A-Za-z0-9_]+
  H5Type type = H5Type::kFloat64;
  // kString columns: fixed width in bytes (1..65535); longer values are refused. 0 when read
  // back from a variable-length string column written by another tool.
  uint32_t string_width = 64;
  bool operator==(const H5Column& o) const {
    return name == o.name && type == o.type &&
           (type != H5Type::kString || string_width == o.string_width);
  }
};
using H5Value = std::variant<double, float, int32_t, int64_t, uint8_t, std::string>;

// True once a file being created was abandoned after an HDF5 failure on it (a failed write: a
// full disk): HDF5 1.10.8 can crash closing such a file, and its own clean-up at exit would, so
// the process should then end without running exit handlers (app/main.cc does).
bool Hdf5FilesAbandoned();

class H5File {
 public:
  // Creates a new file atomically: everything goes to TempPathFor(path) (base/file_util.h) and
  // Commit() closes it and renames it onto `path`. Destroying an uncommitted file deletes the
  // temporary. Creates missing parent directories.
  static H5File Create(const std::string& path, const H5FileOptions& options = {});
  static H5File OpenReadOnly(const std::string& path, const H5FileOptions& options = {});
  // Modifies an existing file in place (appending table rows, adding groups). Not atomic: a
  // crash while writing can leave the file unreadable, so keep what must survive in files
  // written with Create().
  static H5File OpenReadWrite(const std::string& path, const H5FileOptions& options = {});

  H5File(H5File&&) noexcept;
  H5File& operator=(H5File&&) noexcept;
  ~H5File();

  const std::string& path() const;
  bool is_open() const;
  bool writable() const;

  // Created files only: flushes, closes and renames onto path(). The object is closed after.
  void Commit();
  // Writes buffered data to disk (read-write files; for created files it only reaches the
  // temporary).
  void Flush();
  // Closes the file. An uncommitted created file is discarded.
  void Close();

  // ---- Structure
  bool Exists(const std::string& object) const;  // false also when a parent is missing
  bool IsGroup(const std::string& object) const;
  bool IsDataset(const std::string& object) const;
  // Names of a group's members, sorted.
  std::vector<std::string> List(const std::string& group) const;
  // Creates a group and its missing parents; an existing group is fine.
  void CreateGroup(const std::string& group);
  // Copies `object` (a group with everything in it, or a dataset) from `source` to the same
  // path here, whose parents must exist and which must not. Nothing is decoded: a run file's
  // scene is carried from one checkpoint to the next without being held in memory.
  void CopyFrom(const H5File& source, const std::string& object);

  // ---- Arrays (T: double, float, int32_t, int64_t, uint8_t, std::string)
  // Strings are written fixed-width (the longest one's length), UTF-8, NUL-padded, and may not
  // contain NUL; variable-length strings of other writers (h5py's default) are read as well.
  // Writes values (row-major, values.size() == product of shape). Replaces an existing dataset
  // of that name (HDF5 does not reclaim the old space until h5repack).
  template <typename T>
  void Write(const std::string& dataset, const std::vector<T>& values, const H5Shape& shape);
  template <typename T>
  void Write(const std::string& dataset, const std::vector<T>& values) {
    static_assert(kIsH5Element<T>, "H5File: unsupported element type");
    Write(dataset, values, H5Shape{values.size()});
  }
  // Reads a dataset whose shape must match `expected` (same rank; kH5Any matches any extent).
  // The stored type must convert to T without loss: same kind (float / integer / string) and
  // no narrowing (float32 reads as double, int32 as int64, uint8 as int32; not the reverse).
  // Stores the actual shape in *shape if given.
  template <typename T>
  std::vector<T> Read(const std::string& dataset, const H5Shape& expected,
                      H5Shape* shape = nullptr) const;
  H5DatasetInfo Info(const std::string& dataset) const;

  // ---- Scalar attributes on a group or dataset ("/" is the root group). Setting replaces.
  void SetIntAttribute(const std::string& object, const std::string& name, int64_t value);
  void SetDoubleAttribute(const std::string& object, const std::string& name, double value);
  void SetStringAttribute(const std::string& object, const std::string& name,
                          const std::string& value);
  bool HasAttribute(const std::string& object, const std::string& name) const;
  // The stored type must be an integer (any width that fits int64) / float / string.
  int64_t ReadIntAttribute(const std::string& object, const std::string& name) const;
  double ReadDoubleAttribute(const std::string& object, const std::string& name) const;
  std::string ReadStringAttribute(const std::string& object, const std::string& name) const;

  // ---- Appendable tables (per-iteration statistics)
  // A table is a group holding one extendible 1-D dataset per column, all of equal length, and
  // a string attribute "columns" with the comma-separated column names in order. String
  // columns are fixed-width (H5Column::string_width). h5py reads a
  // column as f["stats/time_s"][:]. Fails if the group exists.
  void CreateTable(const std::string& table, const std::vector<H5Column>& columns);
  std::vector<H5Column> TableColumns(const std::string& table) const;
  // Throws if the columns' lengths differ (an append interrupted by a crash).
  uint64_t NumRows(const std::string& table) const;
  // Appends one row: one value per column in column order. A value may widen losslessly to its
  // column's type (int32 -> int64, float -> double, uint8 -> any integer); anything else throws
  // before anything is written.
  void AppendRow(const std::string& table, const std::vector<H5Value>& row);
  // One column, checked to hold NumRows(table) values.
  template <typename T>
  std::vector<T> ReadColumn(const std::string& table, const std::string& column) const;

 private:
  struct Impl;
  explicit H5File(std::unique_ptr<Impl> impl);
  Impl& impl() const;  // throws InputError if closed
  std::unique_ptr<Impl> impl_;
};

// Joins object paths: H5Join("/ckpt", "scene") == "/ckpt/scene", H5Join("/", "views") ==
// "/views".
std::string H5Join(const std::string& parent, const std::string& child);

}  // namespace ms
