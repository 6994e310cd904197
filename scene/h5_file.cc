#include "scene/h5_file.h"

#include <H5Cpp.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <optional>
#include <sstream>
#include <system_error>

#include "base/check.h"
#include "base/error.h"
#include "base/file_util.h"

namespace fs = std::filesystem;

namespace ms {
namespace {

// ---------------------------------------------------------------------------------------------
// Error handling. HDF5 reports failures on a per-thread error stack and, by default, prints it
// to stderr. We switch the printing off (H5::Exception::dontPrint) and install a callback that
// keeps the stack's innermost messages instead, so an InputError can say *why* ("truncated
// file", "file signature not found") rather than only which call failed.

thread_local std::string t_last_hdf5_error;

herr_t CollectErrorEntry(unsigned /*n*/, const H5E_error2_t* entry, void* data) {
  auto* lines = static_cast<std::vector<std::string>*>(data);
  std::string line = entry->desc ? entry->desc : "";
  if (line.empty()) {  // fall back to the generic minor message ("Read failed")
    char minor[160] = "";
    if (H5Eget_msg(entry->min_num, nullptr, minor, sizeof(minor)) > 0) line = minor;
  }
  if (!line.empty()) lines->push_back(line);
  return 0;
}

// Called by HDF5 whenever an API call fails (it replaces the printing handler).
herr_t RecordErrorStack(hid_t stack, void* /*client_data*/) {
  std::vector<std::string> lines;  // outermost (the API call) first
  H5Ewalk2(stack, H5E_WALK_DOWNWARD, CollectErrorEntry, &lines);
  if (lines.empty()) return 0;
  std::string text = lines.back();
  if (lines.size() > 1 && lines.front() != lines.back()) text = lines.front() + ": " + text;
  t_last_hdf5_error = text;
  return 0;
}

// The error-printing setting lives on the thread's error stack (Debian builds HDF5
// thread-safe), so every thread that touches HDF5 sets it once.
void QuietHdf5() {
  thread_local bool quiet = false;
  if (quiet) return;
  H5::Exception::dontPrint();
  H5Eset_auto2(H5E_DEFAULT, RecordErrorStack, nullptr);
  quiet = true;
}

std::string Hdf5Detail(const H5::Exception& e) {
  std::string text = t_last_hdf5_error;
  if (text.empty()) {
    text = e.getFuncName();
    if (!e.getDetailMsg().empty()) text += (text.empty() ? "" : ": ") + e.getDetailMsg();
  }
  if (text.empty()) return "HDF5 error";
  // One line: HDF5's messages (a failed write's, for one) can hold line breaks.
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

// Created files left open after a failure (Impl::Discard), never destroyed.
std::vector<H5::H5File>& AbandonedFiles() {
  static auto* files = new std::vector<H5::H5File>();
  return *files;
}

// C calls report failure by a negative result; turn it into the C++ API's exception so that one
// handler (Impl::Guard) deals with both.
template <typename R>
R Call(R result, const char* function) {
  if (result < 0) throw H5::Exception(function, "failed");
  return result;
}

// ---------------------------------------------------------------------------------------------
// Types.

template <typename T>
constexpr H5Type TypeOf() {
  if constexpr (std::is_same_v<T, double>) return H5Type::kFloat64;
  if constexpr (std::is_same_v<T, float>) return H5Type::kFloat32;
  if constexpr (std::is_same_v<T, int32_t>) return H5Type::kInt32;
  if constexpr (std::is_same_v<T, int64_t>) return H5Type::kInt64;
  if constexpr (std::is_same_v<T, uint8_t>) return H5Type::kUInt8;
  return H5Type::kString;
}

// Only for reading files of other writers (h5py's default): variable-length strings live in
// HDF5's global heap, whose reader crashes on some corrupt heap references (seen with 1.10.8).
// The character set must be the stored one: HDF5 does not convert between ASCII and UTF-8.
H5::StrType VariableStringType(H5T_cset_t cset) {
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(cset);
  return type;
}

// What we write: fixed-width UTF-8, NUL-padded; stored inline, so a damaged file cannot lead
// HDF5 into the global heap.
H5::StrType FixedStringType(size_t width) {
  H5::StrType type(H5::PredType::C_S1, std::max<size_t>(width, 1));
  type.setCset(H5T_CSET_UTF8);
  type.setStrpad(H5T_STR_NULLPAD);
  return type;
}

// Strings packed into `width`-byte NUL-padded cells.
std::vector<char> PackStrings(const std::vector<const std::string*>& strings, size_t width) {
  std::vector<char> buffer(std::max<size_t>(strings.size() * width, 1), '\0');
  for (size_t i = 0; i < strings.size(); ++i) {
    std::memcpy(buffer.data() + i * width, strings[i]->data(), strings[i]->size());
  }
  return buffer;
}

// Type stored in files: fixed little-endian, independent of the writing machine. Strings need
// a width: FixedStringType.
H5::DataType FileType(H5Type type) {
  switch (type) {
    case H5Type::kFloat64:
      return H5::PredType::IEEE_F64LE;
    case H5Type::kFloat32:
      return H5::PredType::IEEE_F32LE;
    case H5Type::kInt32:
      return H5::PredType::STD_I32LE;
    case H5Type::kInt64:
      return H5::PredType::STD_I64LE;
    case H5Type::kUInt8:
      return H5::PredType::STD_U8LE;
    case H5Type::kString:
      break;
  }
  MS_CHECK(false) << "bad H5Type";
  return H5::PredType::IEEE_F64LE;
}

H5::DataType MemoryType(H5Type type) {
  switch (type) {
    case H5Type::kFloat64:
      return H5::PredType::NATIVE_DOUBLE;
    case H5Type::kFloat32:
      return H5::PredType::NATIVE_FLOAT;
    case H5Type::kInt32:
      return H5::PredType::NATIVE_INT32;
    case H5Type::kInt64:
      return H5::PredType::NATIVE_INT64;
    case H5Type::kUInt8:
      return H5::PredType::NATIVE_UINT8;
    case H5Type::kString:
      break;
  }
  MS_CHECK(false) << "bad H5Type";
  return H5::PredType::NATIVE_DOUBLE;
}

size_t MemorySize(H5Type type) {
  switch (type) {
    case H5Type::kFloat64:
      return 8;
    case H5Type::kFloat32:
      return 4;
    case H5Type::kInt32:
      return 4;
    case H5Type::kInt64:
      return 8;
    case H5Type::kUInt8:
      return 1;
    case H5Type::kString:
      return sizeof(std::string);
  }
  return 8;
}

// A readable name for any stored type, for messages.
std::string DescribeStoredType(const H5::DataType& type) {
  const size_t bits = type.getSize() * 8;
  switch (type.getClass()) {
    case H5T_FLOAT:
      return "float" + std::to_string(bits);
    case H5T_INTEGER:
      return (H5Tget_sign(type.getId()) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
    case H5T_STRING:
      return type.isVariableStr() ? "string" : "fixed-length string";
    case H5T_COMPOUND:
      return "compound";
    case H5T_ENUM:
      return "enum";
    case H5T_ARRAY:
      return "array";
    case H5T_VLEN:
      return "variable-length sequence";
    case H5T_REFERENCE:
      return "reference";
    case H5T_OPAQUE:
      return "opaque";
    case H5T_BITFIELD:
      return "bitfield";
    default:
      return "unknown type";
  }
}

// The H5Type a stored type is exactly, if any.
std::optional<H5Type> ExactType(const H5::DataType& type) {
  const size_t size = type.getSize();
  switch (type.getClass()) {
    case H5T_FLOAT:
      if (size == 8) return H5Type::kFloat64;
      if (size == 4) return H5Type::kFloat32;
      return std::nullopt;
    case H5T_INTEGER: {
      const bool is_signed = H5Tget_sign(type.getId()) != H5T_SGN_NONE;
      if (is_signed && size == 4) return H5Type::kInt32;
      if (is_signed && size == 8) return H5Type::kInt64;
      if (!is_signed && size == 1) return H5Type::kUInt8;
      return std::nullopt;
    }
    case H5T_STRING:
      return H5Type::kString;
    default:
      return std::nullopt;
  }
}

// Lossless reads only: same kind, no narrowing.
bool Converts(const H5::DataType& stored, H5Type target) {
  const size_t size = stored.getSize();
  switch (stored.getClass()) {
    case H5T_FLOAT:
      return (target == H5Type::kFloat64 && size <= 8) || (target == H5Type::kFloat32 && size <= 4);
    case H5T_INTEGER: {
      const bool is_signed = H5Tget_sign(stored.getId()) != H5T_SGN_NONE;
      if (target == H5Type::kUInt8) return !is_signed && size <= 1;
      if (target != H5Type::kInt32 && target != H5Type::kInt64) return false;
      const size_t width = MemorySize(target);
      return is_signed ? size <= width : size < width;
    }
    case H5T_STRING:
      return target == H5Type::kString;
    default:
      return false;
  }
}

uint64_t CheckedProduct(const H5Shape& shape, bool* overflow) {
  uint64_t n = 1;
  *overflow = false;
  for (uint64_t d : shape) {
    if (d != 0 && n > std::numeric_limits<uint64_t>::max() / d) *overflow = true;
    n *= d;
  }
  return n;
}

bool ValidColumnName(const std::string& name) {
  if (name.empty()) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// Converts a table cell to its column's type when that loses nothing.
std::optional<H5Value> WidenTo(const H5Value& value, H5Type column) {
  const H5Type have = static_cast<H5Type>(value.index());
  if (have == column) return value;
  switch (column) {
    case H5Type::kFloat64:
      if (const float* f = std::get_if<float>(&value)) return H5Value(double{*f});
      return std::nullopt;
    case H5Type::kInt64:
      if (const int32_t* i = std::get_if<int32_t>(&value)) return H5Value(int64_t{*i});
      if (const uint8_t* u = std::get_if<uint8_t>(&value)) return H5Value(int64_t{*u});
      return std::nullopt;
    case H5Type::kInt32:
      if (const uint8_t* u = std::get_if<uint8_t>(&value)) return H5Value(int32_t{*u});
      return std::nullopt;
    default:
      return std::nullopt;
  }
}

// Upper bound on how much a stored filter pipeline can expand: deflate's maximum ratio is
// 1032:1; the slack covers tiny chunks and unwritten (fill-value) chunks.
constexpr uint64_t kMaxFilterExpansion = 1100;
constexpr uint64_t kFilterSlackBytes = uint64_t{1} << 20;

}  // namespace

static_assert(static_cast<int>(H5Type::kFloat64) == 0 && static_cast<int>(H5Type::kString) == 5,
              "H5Type must follow H5Value's alternatives");
static_assert(std::is_same_v<std::variant_alternative_t<3, H5Value>, int64_t>);

std::string H5TypeName(H5Type type) {
  switch (type) {
    case H5Type::kFloat64:
      return "float64";
    case H5Type::kFloat32:
      return "float32";
    case H5Type::kInt32:
      return "int32";
    case H5Type::kInt64:
      return "int64";
    case H5Type::kUInt8:
      return "uint8";
    case H5Type::kString:
      return "string";
  }
  return "unknown";
}

std::string H5ShapeString(const H5Shape& shape) {
  std::string s = "(";
  for (size_t i = 0; i < shape.size(); ++i) {
    if (i > 0) s += ", ";
    s += shape[i] == kH5Any ? std::string("any") : std::to_string(shape[i]);
  }
  return s + (shape.size() == 1 ? ",)" : ")");
}

std::string H5Join(const std::string& parent, const std::string& child) {
  std::string p = parent;
  while (!p.empty() && p.back() == '/') p.pop_back();
  size_t start = 0;
  while (start < child.size() && child[start] == '/') ++start;
  return p + "/" + child.substr(start);
}

void H5FileOptions::Check() const {
  if (deflate_level < 0 || deflate_level > 9) {
    throw InputError("H5FileOptions.deflate_level must be in 0..9, got " +
                     std::to_string(deflate_level));
  }
  if (chunk_bytes < 1024 || chunk_bytes > (uint64_t{1} << 30)) {
    throw InputError("H5FileOptions.chunk_bytes must be in 1 KiB..1 GiB, got " +
                     std::to_string(chunk_bytes));
  }
  if (table_chunk_rows < 1 || table_chunk_rows > (uint64_t{1} << 20)) {
    throw InputError("H5FileOptions.table_chunk_rows must be in 1..2^20, got " +
                     std::to_string(table_chunk_rows));
  }
  if (max_read_bytes < 1) throw InputError("H5FileOptions.max_read_bytes must be positive");
}

// ---------------------------------------------------------------------------------------------

struct H5File::Impl {
  std::string path;             // what the user named, used in messages
  fs::path temp_path;           // Create(): where the file is written until Commit()
  bool pending = false;         // Create() and not yet committed
  mutable bool failed = false;  // an HDF5 operation on it failed (Guard)
  bool writable = false;
  H5FileOptions options;
  std::optional<H5::H5File> file;

  ~Impl() { Discard(); }

  // Closes without committing; removes an uncommitted temporary. Never throws.
  void Discard() noexcept {
    QuietHdf5();
    if (file && pending && failed) {
      // An unfinished created file discarded after an HDF5 failure, maybe a failed write (a
      // full disk): HDF5 1.10.8 can crash closing such a file (found by the full-disk test), so
      // its handle is left open; the process is about to report the error anyway.
      try {
        AbandonedFiles().push_back(*file);
      } catch (...) {
      }
    } else {
      try {
        if (file) file->close();
      } catch (...) {
      }
    }
    file.reset();
    if (pending) {
      std::error_code ec;
      fs::remove(temp_path, ec);
      pending = false;
    }
  }

  [[noreturn]] void Fail(const std::string& object, const std::string& what) const {
    throw InputError(path + ": " + object + ": " + what);
  }

  // Runs an HDF5 operation; its failures become InputError naming the file and the object.
  template <typename F>
  auto Guard(const std::string& object, const char* action, F&& body) const -> decltype(body()) {
    QuietHdf5();
    t_last_hdf5_error.clear();
    try {
      return body();
    } catch (const H5::Exception& e) {
      failed = true;
      Fail(object, std::string(action) + ": " + Hdf5Detail(e));
    }
  }

  // "/a/b" from "a/b/", "/a//b" etc.; rejects "." and ".." components.
  std::string Normalize(const std::string& object) const {
    std::string out;
    std::stringstream parts(object);
    std::string part;
    while (std::getline(parts, part, '/')) {
      if (part.empty()) continue;
      if (part == "." || part == "..") Fail(object, "'.' and '..' are not allowed in object paths");
      out += "/" + part;
    }
    return out.empty() ? "/" : out;
  }

  void RequireWritable(const std::string& object) const {
    MS_CHECK(writable) << path << ": " << object << ": file is open read-only";
  }

  // Existence, walking down from the root: every parent must be a group and every link must
  // resolve. Throws (via Call) when HDF5 cannot tell, e.g. for a damaged group.
  bool ExistsChecked(const std::string& object) const {
    if (object == "/") return true;
    const hid_t id = file->getId();
    std::string prefix;
    size_t pos = 1;
    while (pos <= object.size()) {
      const size_t next = std::min(object.find('/', pos), object.size());
      if (!prefix.empty() && ObjectType(prefix) != H5O_TYPE_GROUP) return false;
      prefix = object.substr(0, next);
      // A negative answer is an error (a damaged group), not absence.
      if (Call(H5Lexists(id, prefix.c_str(), H5P_DEFAULT), "H5Lexists") == 0) return false;
      if (Call(H5Oexists_by_name(id, prefix.c_str(), H5P_DEFAULT), "H5Oexists_by_name") == 0) {
        return false;  // a dangling soft link
      }
      pos = next + 1;
    }
    return true;
  }

  H5O_type_t ObjectType(const std::string& object) const { return file->childObjType(object); }

  void RequireDataset(const std::string& object) const {
    if (!ExistsChecked(object)) Fail(object, "dataset not found");
    if (ObjectType(object) != H5O_TYPE_DATASET) Fail(object, "is not a dataset");
  }

  void RequireGroup(const std::string& object) const {
    if (!ExistsChecked(object)) Fail(object, "group not found");
    if (ObjectType(object) != H5O_TYPE_GROUP) Fail(object, "is not a group");
  }

  // A group or a dataset, the objects that carry attributes (H5Object cannot be owned through
  // its base class).
  struct OpenedObject {
    std::optional<H5::Group> group;
    std::optional<H5::DataSet> dataset;
    const H5::H5Object& get() const {
      if (group) return *group;
      return *dataset;
    }
    const H5::H5Object* operator->() const { return &get(); }
  };

  OpenedObject OpenObject(const std::string& object) const {
    if (!ExistsChecked(object)) Fail(object, "not found");
    OpenedObject opened;
    switch (ObjectType(object)) {
      case H5O_TYPE_GROUP:
        opened.group.emplace(file->openGroup(object));
        break;
      case H5O_TYPE_DATASET:
        opened.dataset.emplace(file->openDataSet(object));
        break;
      default:
        Fail(object, "is neither a group nor a dataset");
    }
    return opened;
  }

  H5::LinkCreatPropList WithParents() const {
    H5::LinkCreatPropList lcpl;
    lcpl.setCreateIntermediateGroup(true);
    return lcpl;
  }

  // Removes a dataset about to be replaced; refuses to replace a group.
  void PrepareNewDataset(const std::string& object) const {
    if (object == "/") Fail(object, "the root group cannot be replaced by a dataset");
    if (!ExistsChecked(object)) return;
    if (ObjectType(object) != H5O_TYPE_DATASET) Fail(object, "exists and is not a dataset");
    file->unlink(object);
  }

  uint64_t FileSize() const {
    hsize_t size = 0;
    Call(H5Fget_filesize(file->getId(), &size), "H5Fget_filesize");
    return size;
  }

  // Chunked + compressed creation properties for large datasets; contiguous otherwise.
  H5::DSetCreatPropList CreationProperties(const std::vector<hsize_t>& dims,
                                           size_t element_bytes) const {
    H5::DSetCreatPropList dcpl;
    uint64_t n = 1;
    for (hsize_t d : dims) n *= d;
    if (n == 0 || n * element_bytes < options.compress_min_bytes) return dcpl;
    // Chunk: whole inner extents while they fit the budget, then split the outer ones.
    std::vector<hsize_t> chunk(dims.size());
    uint64_t budget = std::max<uint64_t>(1, options.chunk_bytes / element_bytes);
    for (size_t i = dims.size(); i-- > 0;) {
      chunk[i] = std::max<hsize_t>(1, std::min<uint64_t>(dims[i], budget));
      budget = std::max<uint64_t>(1, budget / chunk[i]);
    }
    dcpl.setChunk(static_cast<int>(chunk.size()), chunk.data());
    if (options.deflate_level > 0 && DeflateAvailable()) {
      if (options.shuffle) dcpl.setShuffle();
      dcpl.setDeflate(options.deflate_level);
    }
    return dcpl;
  }

  static bool DeflateAvailable() {
    static const bool available = [] {
      if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0) return false;
      unsigned flags = 0;
      if (H5Zget_filter_info(H5Z_FILTER_DEFLATE, &flags) < 0) return false;
      return (flags & H5Z_FILTER_CONFIG_ENCODE_ENABLED) != 0;
    }();
    return available;
  }

  // Shape of a simple dataspace with rank 1..kH5MaxRank.
  H5Shape ShapeOf(const std::string& object, const H5::DataSpace& space) const {
    if (space.getSimpleExtentType() != H5S_SIMPLE)
      Fail(object, "is a scalar or empty, not an array");
    const int rank = space.getSimpleExtentNdims();
    if (rank < 1 || rank > kH5MaxRank) {
      Fail(object, "has rank " + std::to_string(rank) + "; 1.." + std::to_string(kH5MaxRank) +
                       " is supported");
    }
    std::vector<hsize_t> dims(rank);
    space.getSimpleExtentDims(dims.data());
    return H5Shape(dims.begin(), dims.end());
  }

  // The allocation guard: what the dataset claims must fit what the file stores for it.
  void CheckReadable(const std::string& object, const H5::DataSet& dataset, const H5Shape& shape,
                     size_t stored_element_bytes, size_t memory_element_bytes) const {
    bool overflow = false;
    const uint64_t n = CheckedProduct(shape, &overflow);
    const auto too_big = [&](uint64_t element_bytes) {
      return overflow ||
             (element_bytes != 0 && n > std::numeric_limits<uint64_t>::max() / element_bytes);
    };
    const std::string claim = "claims shape " + H5ShapeString(shape);
    if (too_big(stored_element_bytes) || too_big(memory_element_bytes)) {
      Fail(object, claim + ", too many to address (corrupt file?)");
    }
    const uint64_t memory_bytes = n * memory_element_bytes;
    if (memory_bytes > options.max_read_bytes) {
      Fail(object, claim + " (" + std::to_string(memory_bytes) +
                       " bytes in memory), more than the read limit of " +
                       std::to_string(options.max_read_bytes) + " bytes");
    }
    const uint64_t stored_bytes = n * stored_element_bytes;
    const uint64_t storage = dataset.getStorageSize();
    const uint64_t file_size = FileSize();
    if (storage > file_size) {
      Fail(object, "claims " + std::to_string(storage) + " bytes of storage in a file of " +
                       std::to_string(file_size) + " bytes (corrupt or truncated file)");
    }
    const bool filtered = dataset.getCreatePlist().getNfilters() > 0;
    const uint64_t limit = filtered ? storage * kMaxFilterExpansion + kFilterSlackBytes : storage;
    if (stored_bytes > limit) {
      Fail(object, claim + " (" + std::to_string(stored_bytes) + " bytes) but the file holds " +
                       std::to_string(storage) +
                       " bytes of data for it (corrupt file, or a dataset never written)");
    }
  }

  template <typename T>
  std::vector<T> ReadNumbers(const H5::DataSet& dataset, const H5::DataSpace& space,
                             uint64_t n) const {
    std::vector<T> values(n);
    if (n > 0) dataset.read(values.data(), MemoryType(TypeOf<T>()), space, space);
    return values;
  }

  std::vector<std::string> ReadStrings(const H5::DataSet& dataset, const H5::DataSpace& space,
                                       const H5::DataType& stored, uint64_t n) const {
    std::vector<std::string> values(n);
    if (n == 0) return values;
    if (stored.isVariableStr()) {
      const H5::StrType memory = VariableStringType(H5Tget_cset(stored.getId()));
      std::vector<char*> buffer(n, nullptr);
      struct Reclaim {  // frees HDF5's strings whatever happens (null entries are skipped)
        std::vector<char*>& b;
        const H5::DataType& t;
        const H5::DataSpace& s;
        ~Reclaim() { H5Dvlen_reclaim(t.getId(), s.getId(), H5P_DEFAULT, b.data()); }
      } reclaim{buffer, memory, space};
      dataset.read(buffer.data(), memory, space, space);
      for (uint64_t i = 0; i < n; ++i) {
        if (buffer[i]) values[i] = buffer[i];
      }
    } else {
      const size_t width = stored.getSize();
      std::vector<char> buffer(n * width);
      // Strings have no byte order: the stored type (width, padding, character set) serves as
      // the memory type too (HDF5 has no ASCII <-> UTF-8 conversion).
      dataset.read(buffer.data(), stored, space, space);
      const bool space_padded = H5Tget_strpad(stored.getId()) == H5T_STR_SPACEPAD;
      for (uint64_t i = 0; i < n; ++i)
        values[i] = FixedString(buffer.data() + i * width, width, space_padded);
    }
    return values;
  }

  static std::string FixedString(const char* data, size_t width, bool space_padded) {
    size_t length = space_padded ? width : strnlen(data, width);
    if (space_padded) {
      while (length > 0 && data[length - 1] == ' ') --length;
    }
    return std::string(data, length);
  }

  std::unique_ptr<H5::Attribute> OpenAttribute(const std::string& object, const std::string& name,
                                               const H5::H5Object& owner) const {
    if (!owner.attrExists(name)) Fail(object, "attribute '" + name + "' not found");
    auto attribute = std::make_unique<H5::Attribute>(owner.openAttribute(name));
    const H5::DataSpace space = attribute->getSpace();
    const bool scalar =
        space.getSimpleExtentType() == H5S_SCALAR ||
        (space.getSimpleExtentType() == H5S_SIMPLE && space.getSimpleExtentNpoints() == 1);
    if (!scalar) Fail(object, "attribute '" + name + "' is not a single value");
    return attribute;
  }

  void SetAttribute(const std::string& object, const std::string& name, const H5::DataType& type,
                    const void* value) {
    RequireWritable(object);
    Guard(object, ("cannot write attribute '" + name + "'").c_str(), [&] {
      const OpenedObject owner = OpenObject(object);
      if (owner->attrExists(name)) owner->removeAttr(name);
      H5::Attribute attribute = owner->createAttribute(name, type, H5::DataSpace(H5S_SCALAR));
      attribute.write(type, value);
    });
  }

  template <typename T>
  T ReadNumericAttribute(const std::string& object, const std::string& name, H5T_class_t kind,
                         const H5::DataType& memory) const {
    return Guard(object, ("cannot read attribute '" + name + "'").c_str(), [&] {
      const OpenedObject owner = OpenObject(object);
      const std::unique_ptr<H5::Attribute> attribute = OpenAttribute(object, name, owner.get());
      const H5::DataType stored = attribute->getDataType();
      bool ok = stored.getClass() == kind && stored.getSize() <= sizeof(T);
      if (kind == H5T_INTEGER && ok && stored.getSize() == 8) {
        ok = H5Tget_sign(stored.getId()) != H5T_SGN_NONE;  // uint64 may not fit int64
      }
      if (!ok) {
        Fail(object, "attribute '" + name + "' is " + DescribeStoredType(stored) + ", expected " +
                         (kind == H5T_INTEGER ? "an integer" : "a floating-point number"));
      }
      T value{};
      attribute->read(memory, &value);
      return value;
    });
  }

  std::string StringValue(const std::string& object, const std::string& name,
                          const H5::Attribute& attribute) const {
    const H5::DataType stored = attribute.getDataType();
    if (stored.getClass() != H5T_STRING) {
      Fail(object,
           "attribute '" + name + "' is " + DescribeStoredType(stored) + ", expected a string");
    }
    if (stored.isVariableStr()) {
      const H5::StrType memory = VariableStringType(H5Tget_cset(stored.getId()));
      char* text = nullptr;
      attribute.read(memory, &text);
      std::string value = text ? text : "";
      H5free_memory(text);
      return value;
    }
    const size_t width = stored.getSize();
    if (width > FileSize()) Fail(object, "attribute '" + name + "' is corrupt");
    std::vector<char> buffer(width);
    attribute.read(stored, buffer.data());
    return FixedString(buffer.data(), width, H5Tget_strpad(stored.getId()) == H5T_STR_SPACEPAD);
  }

  std::vector<H5Column> Columns(const std::string& table) const;
  uint64_t Rows(const std::string& table, const std::vector<H5Column>& columns) const;
};

// ---------------------------------------------------------------------------------------------

namespace {

H5::FileAccPropList MakeAccessProperties() {
  H5::FileAccPropList fapl;
  // Closing the file closes everything in it, so Commit() never renames a file still open.
  fapl.setFcloseDegree(H5F_CLOSE_STRONG);
  // The HDF5 1.10 file format: all metadata checksummed, chunk indexes included, so damage is
  // detected instead of misread (or crashing the reader). Readable by HDF5 >= 1.10 (h5py too).
  fapl.setLibverBounds(H5F_LIBVER_V110, H5F_LIBVER_V110);
  // Lock files, but do not fail on file systems without locks (NFS, some containers).
  H5Pset_file_locking(fapl.getId(), true, true);
  return fapl;
}

}  // namespace

bool Hdf5FilesAbandoned() { return !AbandonedFiles().empty(); }

H5File::H5File(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
H5File::H5File(H5File&&) noexcept = default;
H5File& H5File::operator=(H5File&&) noexcept = default;
H5File::~H5File() = default;

H5File::Impl& H5File::impl() const {
  MS_CHECK(impl_ != nullptr) << "H5File used after move";
  MS_CHECK(impl_->file.has_value()) << impl_->path << ": H5File used after Close/Commit";
  return *impl_;
}

H5File H5File::Create(const std::string& path, const H5FileOptions& options) {
  options.Check();
  QuietHdf5();
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->options = options;
  impl->writable = true;
  impl->temp_path = TempPathFor(path);
  std::error_code ec;
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty()) fs::create_directories(parent, ec);
  t_last_hdf5_error.clear();
  try {
    impl->file.emplace(impl->temp_path.string(), H5F_ACC_TRUNC, H5::FileCreatPropList::DEFAULT,
                       MakeAccessProperties());
    impl->pending = true;
  } catch (const H5::Exception& e) {
    std::error_code ignored;
    fs::remove(impl->temp_path, ignored);
    throw InputError(path + ": cannot create HDF5 file (" + impl->temp_path.string() +
                     "): " + Hdf5Detail(e));
  }
  return H5File(std::move(impl));
}

namespace {

H5::H5File OpenExisting(const std::string& path, unsigned flags) {
  QuietHdf5();
  RequireFile(path, "HDF5 file");
  t_last_hdf5_error.clear();
  const htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
  if (is_hdf5 == 0) throw InputError(path + ": not an HDF5 file (no HDF5 signature)");
  if (is_hdf5 < 0) throw InputError(path + ": cannot open HDF5 file: " + t_last_hdf5_error);
  try {
    return H5::H5File(path, flags, H5::FileCreatPropList::DEFAULT, MakeAccessProperties());
  } catch (const H5::Exception& e) {
    throw InputError(path + ": cannot open HDF5 file: " + Hdf5Detail(e));
  }
}

}  // namespace

H5File H5File::OpenReadOnly(const std::string& path, const H5FileOptions& options) {
  options.Check();
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->options = options;
  impl->file.emplace(OpenExisting(path, H5F_ACC_RDONLY));
  return H5File(std::move(impl));
}

H5File H5File::OpenReadWrite(const std::string& path, const H5FileOptions& options) {
  options.Check();
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->options = options;
  impl->writable = true;
  impl->file.emplace(OpenExisting(path, H5F_ACC_RDWR));
  return H5File(std::move(impl));
}

const std::string& H5File::path() const {
  MS_CHECK(impl_ != nullptr) << "H5File used after move";
  return impl_->path;
}
bool H5File::is_open() const { return impl_ && impl_->file.has_value(); }
bool H5File::writable() const { return is_open() && impl_->writable; }

void H5File::Commit() {
  Impl& im = impl();
  MS_CHECK(im.pending) << im.path << ": Commit() is for files made with H5File::Create";
  im.Guard("/", "cannot finish writing", [&] {
    im.file->flush(H5F_SCOPE_GLOBAL);
    im.file->close();
  });
  im.file.reset();
  im.pending = false;
  CommitTempFile(im.temp_path, im.path);
}

void H5File::Flush() {
  Impl& im = impl();
  im.Guard("/", "cannot flush", [&] { im.file->flush(H5F_SCOPE_GLOBAL); });
}

void H5File::Close() {
  if (!impl_ || !impl_->file) return;
  Impl& im = *impl_;
  if (im.pending) {
    im.Discard();
    return;
  }
  im.Guard("/", "cannot close", [&] { im.file->close(); });
  im.file.reset();
}

bool H5File::Exists(const std::string& object) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(object);
  return im.Guard(name, "cannot look up", [&] { return im.ExistsChecked(name); });
}

bool H5File::IsGroup(const std::string& object) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(object);
  return im.Guard(name, "cannot look up",
                  [&] { return im.ExistsChecked(name) && im.ObjectType(name) == H5O_TYPE_GROUP; });
}

bool H5File::IsDataset(const std::string& object) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(object);
  return im.Guard(name, "cannot look up", [&] {
    return im.ExistsChecked(name) && im.ObjectType(name) == H5O_TYPE_DATASET;
  });
}

std::vector<std::string> H5File::List(const std::string& group) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(group);
  return im.Guard(name, "cannot list group", [&] {
    im.RequireGroup(name);
    const H5::Group g = im.file->openGroup(name);
    const hsize_t n = g.getNumObjs();
    std::vector<std::string> names;
    for (hsize_t i = 0; i < n; ++i) names.push_back(g.getObjnameByIdx(i));
    std::sort(names.begin(), names.end());
    return names;
  });
}

void H5File::CopyFrom(const H5File& source, const std::string& object) {
  Impl& im = impl();
  const Impl& from = source.impl();
  const std::string name = im.Normalize(object);
  im.RequireWritable(name);
  if (!from.ExistsChecked(name)) from.Fail(name, "not found (copying it to " + im.path + ")");
  if (im.ExistsChecked(name)) im.Fail(name, "exists already (copying it from " + from.path + ")");
  im.Guard(name, ("cannot copy it from " + from.path).c_str(), [&] {
    if (H5Ocopy(from.file->getId(), name.c_str(), im.file->getId(), name.c_str(), H5P_DEFAULT,
                H5P_DEFAULT) < 0) {
      throw H5::Exception("H5Ocopy", "the copy failed");
    }
  });
}

void H5File::CreateGroup(const std::string& group) {
  Impl& im = impl();
  const std::string name = im.Normalize(group);
  im.RequireWritable(name);
  im.Guard(name, "cannot create group", [&] {
    if (im.ExistsChecked(name)) {
      if (im.ObjectType(name) != H5O_TYPE_GROUP) im.Fail(name, "exists and is not a group");
      return;
    }
    im.file->createGroup(name, im.WithParents());
  });
}

template <typename T>
void H5File::Write(const std::string& dataset, const std::vector<T>& values, const H5Shape& shape) {
  static_assert(kIsH5Element<T>, "H5File::Write: unsupported element type");
  Impl& im = impl();
  const std::string name = im.Normalize(dataset);
  im.RequireWritable(name);
  bool overflow = false;
  MS_CHECK(!shape.empty() && static_cast<int>(shape.size()) <= kH5MaxRank &&
           CheckedProduct(shape, &overflow) == values.size() && !overflow)
      << im.path << ": " << name << ": " << values.size() << " values do not fill shape "
      << H5ShapeString(shape);
  size_t width = 1;  // strings: the longest one
  if constexpr (std::is_same_v<T, std::string>) {
    for (size_t i = 0; i < values.size(); ++i) {
      if (values[i].find('\0') != std::string::npos) {
        im.Fail(name, "string " + std::to_string(i) + " contains a NUL byte");
      }
      width = std::max(width, values[i].size());
    }
  }
  im.Guard(name, "cannot write dataset", [&] {
    const std::vector<hsize_t> dims(shape.begin(), shape.end());
    const H5::DataSpace space(static_cast<int>(dims.size()), dims.data());
    const H5::DataType file_type = std::is_same_v<T, std::string>
                                       ? H5::DataType(FixedStringType(width))
                                       : FileType(TypeOf<T>());
    const size_t stored_bytes = std::is_same_v<T, std::string> ? width : sizeof(T);
    const H5::DSetCreatPropList dcpl = im.CreationProperties(dims, stored_bytes);
    im.PrepareNewDataset(name);
    const H5::DataSet ds = im.file->createDataSet(name, file_type, space, dcpl,
                                                  H5::DSetAccPropList::DEFAULT, im.WithParents());
    if (values.empty()) return;
    if constexpr (std::is_same_v<T, std::string>) {
      std::vector<const std::string*> strings;
      for (const std::string& value : values) strings.push_back(&value);
      ds.write(PackStrings(strings, width).data(), file_type);
    } else {
      ds.write(values.data(), MemoryType(TypeOf<T>()));
    }
  });
}

template <typename T>
std::vector<T> H5File::Read(const std::string& dataset, const H5Shape& expected,
                            H5Shape* shape) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(dataset);
  return im.Guard(name, "cannot read dataset", [&] {
    im.RequireDataset(name);
    const H5::DataSet ds = im.file->openDataSet(name);
    const H5::DataSpace space = ds.getSpace();
    const H5Shape actual = im.ShapeOf(name, space);
    bool matches = actual.size() == expected.size();
    for (size_t i = 0; matches && i < actual.size(); ++i) {
      matches = expected[i] == kH5Any || expected[i] == actual[i];
    }
    if (!matches) {
      im.Fail(name, "has shape " + H5ShapeString(actual) + ", expected " + H5ShapeString(expected));
    }
    const H5::DataType stored = ds.getDataType();
    if (!Converts(stored, TypeOf<T>())) {
      im.Fail(name, "is stored as " + DescribeStoredType(stored) + ", cannot read it as " +
                        H5TypeName(TypeOf<T>()) + " without loss");
    }
    const size_t memory_bytes =
        std::is_same_v<T, std::string> ? sizeof(std::string) + stored.getSize() : sizeof(T);
    im.CheckReadable(name, ds, actual, stored.getSize(), memory_bytes);
    if (shape) *shape = actual;
    bool overflow = false;
    const uint64_t n = CheckedProduct(actual, &overflow);
    if constexpr (std::is_same_v<T, std::string>) {
      return im.ReadStrings(ds, space, stored, n);
    } else {
      return im.ReadNumbers<T>(ds, space, n);
    }
  });
}

H5DatasetInfo H5File::Info(const std::string& dataset) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(dataset);
  return im.Guard(name, "cannot inspect dataset", [&] {
    im.RequireDataset(name);
    const H5::DataSet ds = im.file->openDataSet(name);
    const H5::DataSpace space = ds.getSpace();
    H5DatasetInfo info;
    info.shape = im.ShapeOf(name, space);
    const H5::DataType stored = ds.getDataType();
    const std::optional<H5Type> type = ExactType(stored);
    if (!type) im.Fail(name, "has unsupported element type " + DescribeStoredType(stored));
    info.type = *type;
    bool overflow = false;
    info.num_elements = CheckedProduct(info.shape, &overflow);
    if (overflow) im.Fail(name, "claims too many elements to address (corrupt file?)");
    const H5::DSetCreatPropList dcpl = ds.getCreatePlist();
    info.chunked = dcpl.getLayout() == H5D_CHUNKED;
    info.compressed = dcpl.getNfilters() > 0;
    std::vector<hsize_t> max_dims(info.shape.size());
    space.getSimpleExtentDims(nullptr, max_dims.data());
    info.extendible =
        std::any_of(max_dims.begin(), max_dims.end(), [](hsize_t d) { return d == H5S_UNLIMITED; });
    return info;
  });
}

// ---- Attributes

void H5File::SetIntAttribute(const std::string& object, const std::string& name, int64_t value) {
  Impl& im = impl();
  im.SetAttribute(im.Normalize(object), name, H5::PredType::STD_I64LE, &value);
}

void H5File::SetDoubleAttribute(const std::string& object, const std::string& name, double value) {
  Impl& im = impl();
  im.SetAttribute(im.Normalize(object), name, H5::PredType::IEEE_F64LE, &value);
}

void H5File::SetStringAttribute(const std::string& object, const std::string& name,
                                const std::string& value) {
  Impl& im = impl();
  const std::string normalized = im.Normalize(object);
  if (value.find('\0') != std::string::npos) {
    im.Fail(normalized, "attribute '" + name + "' contains a NUL byte");
  }
  std::vector<char> buffer(value.begin(), value.end());
  buffer.push_back('\0');  // width max(1, size): the padding byte for an empty string
  im.SetAttribute(normalized, name, FixedStringType(value.size()), buffer.data());
}

bool H5File::HasAttribute(const std::string& object, const std::string& name) const {
  const Impl& im = impl();
  const std::string normalized = im.Normalize(object);
  return im.Guard(normalized, "cannot look up attributes", [&] {
    if (!im.ExistsChecked(normalized)) return false;
    return im.OpenObject(normalized)->attrExists(name);
  });
}

int64_t H5File::ReadIntAttribute(const std::string& object, const std::string& name) const {
  const Impl& im = impl();
  return im.ReadNumericAttribute<int64_t>(im.Normalize(object), name, H5T_INTEGER,
                                          H5::PredType::NATIVE_INT64);
}

double H5File::ReadDoubleAttribute(const std::string& object, const std::string& name) const {
  const Impl& im = impl();
  return im.ReadNumericAttribute<double>(im.Normalize(object), name, H5T_FLOAT,
                                         H5::PredType::NATIVE_DOUBLE);
}

std::string H5File::ReadStringAttribute(const std::string& object, const std::string& name) const {
  const Impl& im = impl();
  const std::string normalized = im.Normalize(object);
  return im.Guard(normalized, ("cannot read attribute '" + name + "'").c_str(), [&] {
    const Impl::OpenedObject owner = im.OpenObject(normalized);
    const std::unique_ptr<H5::Attribute> attribute =
        im.OpenAttribute(normalized, name, owner.get());
    return im.StringValue(normalized, name, *attribute);
  });
}

// ---- Tables

std::vector<H5Column> H5File::Impl::Columns(const std::string& table) const {
  RequireGroup(table);
  const H5::Group group = file->openGroup(table);
  if (!group.attrExists("columns")) Fail(table, "is not a table (no 'columns' attribute)");
  std::vector<H5Column> columns;
  std::string list;
  list = StringValue(table, "columns", *OpenAttribute(table, "columns", group));
  std::stringstream parts(list);
  std::string name;
  while (std::getline(parts, name, ',')) {
    if (!ValidColumnName(name)) Fail(table, "bad column name '" + name + "' in 'columns'");
    const std::string object = table == "/" ? "/" + name : table + "/" + name;
    if (!ExistsChecked(object) || ObjectType(object) != H5O_TYPE_DATASET) {
      Fail(object, "table column dataset not found");
    }
    const H5::DataSet ds = file->openDataSet(object);
    const H5::DataSpace space = ds.getSpace();
    const H5Shape shape = ShapeOf(object, space);
    if (shape.size() != 1) Fail(object, "table column is not 1-D");
    const H5::DataType stored = ds.getDataType();
    const std::optional<H5Type> type = ExactType(stored);
    if (!type) Fail(object, "table column has unsupported type " + DescribeStoredType(stored));
    const uint32_t width =
        *type == H5Type::kString && !stored.isVariableStr() ? stored.getSize() : 0;
    columns.push_back({name, *type, width});
  }
  if (columns.empty()) Fail(table, "table has no columns");
  return columns;
}

uint64_t H5File::Impl::Rows(const std::string& table, const std::vector<H5Column>& columns) const {
  uint64_t rows = 0;
  for (size_t i = 0; i < columns.size(); ++i) {
    const std::string object = H5Join(table, columns[i].name);
    const uint64_t n = ShapeOf(object, file->openDataSet(object).getSpace())[0];
    if (i == 0) {
      rows = n;
    } else if (n != rows) {
      Fail(table, "table columns have different lengths ('" + columns[0].name + "' " +
                      std::to_string(rows) + ", '" + columns[i].name + "' " + std::to_string(n) +
                      "; an interrupted append?)");
    }
  }
  return rows;
}

void H5File::CreateTable(const std::string& table, const std::vector<H5Column>& columns) {
  Impl& im = impl();
  const std::string name = im.Normalize(table);
  im.RequireWritable(name);
  if (columns.empty()) im.Fail(name, "a table needs at least one column");
  for (size_t i = 0; i < columns.size(); ++i) {
    if (columns[i].type == H5Type::kString &&
        (columns[i].string_width < 1 || columns[i].string_width > 65535)) {
      im.Fail(name, "string column '" + columns[i].name + "' needs a string_width in 1..65535");
    }
    if (!ValidColumnName(columns[i].name)) {
      im.Fail(name, "bad column name '" + columns[i].name + "' (use [A-Za-z0-9_])");
    }
    for (size_t j = 0; j < i; ++j) {
      if (columns[j].name == columns[i].name)
        im.Fail(name, "duplicate column '" + columns[i].name + "'");
    }
  }
  im.Guard(name, "cannot create table", [&] {
    if (im.ExistsChecked(name)) im.Fail(name, "already exists");
    const H5::Group group = im.file->createGroup(name, im.WithParents());
    std::string list;
    for (const H5Column& column : columns) {
      const hsize_t dims[1] = {0};
      const hsize_t max_dims[1] = {H5S_UNLIMITED};
      const H5::DataSpace space(1, dims, max_dims);
      H5::DSetCreatPropList dcpl;
      const hsize_t chunk[1] = {im.options.table_chunk_rows};
      dcpl.setChunk(1, chunk);
      group.createDataSet(column.name,
                          column.type == H5Type::kString
                              ? H5::DataType(FixedStringType(column.string_width))
                              : FileType(column.type),
                          space, dcpl);
      list += (list.empty() ? "" : ",") + column.name;
    }
    const H5::StrType type = FixedStringType(list.size());
    group.createAttribute("columns", type, H5::DataSpace(H5S_SCALAR)).write(type, list.c_str());
  });
}

std::vector<H5Column> H5File::TableColumns(const std::string& table) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(table);
  return im.Guard(name, "cannot read table", [&] { return im.Columns(name); });
}

uint64_t H5File::NumRows(const std::string& table) const {
  const Impl& im = impl();
  const std::string name = im.Normalize(table);
  return im.Guard(name, "cannot read table", [&] { return im.Rows(name, im.Columns(name)); });
}

void H5File::AppendRow(const std::string& table, const std::vector<H5Value>& row) {
  Impl& im = impl();
  const std::string name = im.Normalize(table);
  im.RequireWritable(name);
  im.Guard(name, "cannot append to table", [&] {
    const std::vector<H5Column> columns = im.Columns(name);
    const uint64_t rows = im.Rows(name, columns);
    if (row.size() != columns.size()) {
      im.Fail(name, "row has " + std::to_string(row.size()) + " values for " +
                        std::to_string(columns.size()) + " columns");
    }
    // Everything is checked before the first write, so a bad row leaves the table as it was.
    std::vector<H5Value> cells;
    for (size_t i = 0; i < columns.size(); ++i) {
      std::optional<H5Value> cell = WidenTo(row[i], columns[i].type);
      if (!cell) {
        im.Fail(name, "column '" + columns[i].name + "' is " + H5TypeName(columns[i].type) +
                          ", got a " + H5TypeName(static_cast<H5Type>(row[i].index())));
      }
      if (const std::string* s = std::get_if<std::string>(&*cell)) {
        if (s->find('\0') != std::string::npos) {
          im.Fail(name, "column '" + columns[i].name + "': string contains a NUL byte");
        }
        if (columns[i].string_width > 0 && s->size() > columns[i].string_width) {
          im.Fail(name, "column '" + columns[i].name + "' holds strings of at most " +
                            std::to_string(columns[i].string_width) + " bytes, got " +
                            std::to_string(s->size()));
        }
      }
      cells.push_back(std::move(*cell));
    }
    for (size_t i = 0; i < columns.size(); ++i) {
      H5::DataSet ds = im.file->openDataSet(H5Join(name, columns[i].name));
      const hsize_t size[1] = {rows + 1};
      ds.extend(size);
      H5::DataSpace file_space = ds.getSpace();
      const hsize_t offset[1] = {rows};
      const hsize_t count[1] = {1};
      file_space.selectHyperslab(H5S_SELECT_SET, count, offset);
      const H5::DataSpace memory_space(1, count);
      std::visit(
          [&](const auto& value) {
            using V = std::decay_t<decltype(value)>;
            if constexpr (std::is_same_v<V, std::string>) {
              if (columns[i].string_width > 0) {
                const H5::StrType memory = FixedStringType(columns[i].string_width);
                ds.write(PackStrings({&value}, columns[i].string_width).data(), memory,
                         memory_space, file_space);
              } else {  // a variable-length column of another writer
                const char* pointer = value.c_str();
                ds.write(&pointer, VariableStringType(H5Tget_cset(ds.getDataType().getId())),
                         memory_space, file_space);
              }
            } else {
              ds.write(&value, MemoryType(columns[i].type), memory_space, file_space);
            }
          },
          cells[i]);
    }
  });
}

template <typename T>
std::vector<T> H5File::ReadColumn(const std::string& table, const std::string& column) const {
  const uint64_t rows = NumRows(table);
  const std::vector<H5Column> columns = TableColumns(table);
  if (std::none_of(columns.begin(), columns.end(),
                   [&](const H5Column& c) { return c.name == column; })) {
    impl().Fail(impl().Normalize(table), "table has no column '" + column + "'");
  }
  return Read<T>(H5Join(impl().Normalize(table), column), {rows});
}

#define MS_INSTANTIATE_H5(T)                                                                   \
  template void H5File::Write<T>(const std::string&, const std::vector<T>&, const H5Shape&);   \
  template std::vector<T> H5File::Read<T>(const std::string&, const H5Shape&, H5Shape*) const; \
  template std::vector<T> H5File::ReadColumn<T>(const std::string&, const std::string&) const;
MS_INSTANTIATE_H5(double)
MS_INSTANTIATE_H5(float)
MS_INSTANTIATE_H5(int32_t)
MS_INSTANTIATE_H5(int64_t)
MS_INSTANTIATE_H5(uint8_t)
MS_INSTANTIATE_H5(std::string)
#undef MS_INSTANTIATE_H5

}  // namespace ms
