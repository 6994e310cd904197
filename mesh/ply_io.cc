#include "mesh/ply_io.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>

#include "base/binary_reader.h"
#include "base/error.h"
#include "base/text_reader.h"

#ifndef MS_VERSION
#define MS_VERSION "unknown"
#endif

namespace ms {
namespace {

// ---------------------------------------------------------------------------------------------
// Types and header model.

enum class PlyType : uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kFloat32,
  kFloat64
};

size_t TypeSize(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 1;
}

bool IsIntegerType(PlyType t) { return t != PlyType::kFloat32 && t != PlyType::kFloat64; }

int64_t TypeMin(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
      return INT8_MIN;
    case PlyType::kInt16:
      return INT16_MIN;
    case PlyType::kInt32:
      return INT32_MIN;
    default:
      return 0;
  }
}

int64_t TypeMax(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
      return INT8_MAX;
    case PlyType::kUint8:
      return UINT8_MAX;
    case PlyType::kInt16:
      return INT16_MAX;
    case PlyType::kUint16:
      return UINT16_MAX;
    case PlyType::kInt32:
      return INT32_MAX;
    case PlyType::kUint32:
      return UINT32_MAX;
    default:
      return 0;
  }
}

std::optional<PlyType> ParseTypeName(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::kInt8;
  if (s == "uchar" || s == "uint8") return PlyType::kUint8;
  if (s == "short" || s == "int16") return PlyType::kInt16;
  if (s == "ushort" || s == "uint16") return PlyType::kUint16;
  if (s == "int" || s == "int32") return PlyType::kInt32;
  if (s == "uint" || s == "uint32") return PlyType::kUint32;
  if (s == "float" || s == "float32") return PlyType::kFloat32;
  if (s == "double" || s == "float64") return PlyType::kFloat64;
  return std::nullopt;
}

// Where a property's value goes.
enum class Slot : uint8_t {
  kSkip,
  kX,
  kY,
  kZ,
  kNx,
  kNy,
  kNz,
  kRed,
  kGreen,
  kBlue,
  kScalar,
  kIndices
};

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // the item type for lists
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
  Slot slot = Slot::kSkip;
  int line = 0;  // header line, for errors
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  int line = 0;
};

enum class PlyEncoding { kAscii, kBinaryLittle, kBinaryBig };

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::kAscii;
  std::vector<PlyElement> elements;
  size_t data_offset = 0;  // first byte after "end_header\n"
  int num_lines = 0;       // header lines, end_header included
};

constexpr size_t kMaxHeaderBytes = size_t{1} << 20;

[[noreturn]] void FailAtLine(const std::string& name, int line, const std::string& message) {
  throw InputError(name + ":" + std::to_string(line) + ": " + message);
}

std::vector<std::string_view> Words(std::string_view line) { return SplitFields(line); }

PlyHeader ParseHeader(std::string_view data, const std::string& name) {
  PlyHeader header;
  size_t pos = 0;
  int line_number = 0;
  bool have_format = false;
  auto next_line = [&](std::string_view* line) {
    if (pos >= data.size() || pos >= kMaxHeaderBytes) return false;
    size_t end = data.find('\n', pos);
    if (end == std::string_view::npos) return false;  // a header line always ends with '\n'
    std::string_view view = data.substr(pos, end - pos);
    if (!view.empty() && view.back() == '\r') view.remove_suffix(1);
    pos = end + 1;
    ++line_number;
    *line = view;
    return true;
  };
  std::string_view line;
  if (!next_line(&line) || Trim(line) != "ply") {
    throw InputError(name + ": not a PLY file (the first line is not 'ply')");
  }
  while (true) {
    if (!next_line(&line)) {
      FailAtLine(name, line_number + 1,
                 "header has no 'end_header' line (within the first " +
                     std::to_string(kMaxHeaderBytes) + " bytes)");
    }
    const std::vector<std::string_view> w = Words(line);
    if (w.empty()) continue;
    const std::string_view key = w[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      if (w.size() != 1) FailAtLine(name, line_number, "unexpected words after 'end_header'");
      break;
    }
    if (key == "format") {
      if (have_format) FailAtLine(name, line_number, "second 'format' line");
      if (w.size() != 3) FailAtLine(name, line_number, "expected 'format <encoding> 1.0'");
      if (w[1] == "ascii") {
        header.encoding = PlyEncoding::kAscii;
      } else if (w[1] == "binary_little_endian") {
        header.encoding = PlyEncoding::kBinaryLittle;
      } else if (w[1] == "binary_big_endian") {
        header.encoding = PlyEncoding::kBinaryBig;
      } else {
        FailAtLine(name, line_number, "unknown format '" + std::string(w[1]) + "'");
      }
      if (w[2].substr(0, 2) != "1.") {
        FailAtLine(name, line_number, "unsupported PLY version '" + std::string(w[2]) + "'");
      }
      have_format = true;
      continue;
    }
    if (!have_format)
      FailAtLine(name, line_number, "'format' must come before '" + std::string(key) + "'");
    if (key == "element") {
      if (w.size() != 3) FailAtLine(name, line_number, "expected 'element <name> <count>'");
      PlyElement element;
      element.name = std::string(w[1]);
      element.line = line_number;
      uint64_t count = 0;
      const auto [ptr, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), count);
      if (ec != std::errc() || ptr != w[2].data() + w[2].size()) {
        FailAtLine(name, line_number,
                   "element " + element.name + ": count '" + std::string(w[2]) +
                       "' is not a non-negative integer");
      }
      element.count = count;
      for (const PlyElement& other : header.elements) {
        if (other.name == element.name) {
          FailAtLine(name, line_number, "element " + element.name + " declared twice");
        }
      }
      header.elements.push_back(std::move(element));
      continue;
    }
    if (key == "property") {
      if (header.elements.empty()) FailAtLine(name, line_number, "property before any element");
      PlyElement& element = header.elements.back();
      PlyProperty property;
      property.line = line_number;
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5) {
          FailAtLine(name, line_number, "expected 'property list <count type> <item type> <name>'");
        }
        const auto count_type = ParseTypeName(w[2]);
        const auto item_type = ParseTypeName(w[3]);
        if (!count_type) FailAtLine(name, line_number, "unknown type '" + std::string(w[2]) + "'");
        if (!item_type) FailAtLine(name, line_number, "unknown type '" + std::string(w[3]) + "'");
        if (!IsIntegerType(*count_type)) {
          FailAtLine(name, line_number, "list count type must be an integer type");
        }
        property.is_list = true;
        property.count_type = *count_type;
        property.type = *item_type;
        property.name = std::string(w[4]);
      } else {
        if (w.size() != 3) FailAtLine(name, line_number, "expected 'property <type> <name>'");
        const auto type = ParseTypeName(w[1]);
        if (!type) FailAtLine(name, line_number, "unknown type '" + std::string(w[1]) + "'");
        property.type = *type;
        property.name = std::string(w[2]);
      }
      for (const PlyProperty& other : element.properties) {
        if (other.name == property.name) {
          FailAtLine(name, line_number,
                     "element " + element.name + ": property " + property.name + " declared twice");
        }
      }
      element.properties.push_back(std::move(property));
      continue;
    }
    FailAtLine(name, line_number, "unknown header keyword '" + std::string(key) + "'");
  }
  if (!have_format) FailAtLine(name, line_number, "header has no 'format' line");
  header.data_offset = pos;
  header.num_lines = line_number;
  return header;
}

// Smallest number of bytes one instance of `element` can occupy in the data section.
uint64_t MinInstanceBytes(const PlyElement& element, PlyEncoding encoding) {
  uint64_t bytes = 0;
  for (const PlyProperty& p : element.properties) {
    if (encoding == PlyEncoding::kAscii) {
      bytes += 2;  // one character and one separator per value at least
    } else {
      bytes += p.is_list ? TypeSize(p.count_type) : TypeSize(p.type);
    }
  }
  return bytes;
}

// Counts claimed by the header must fit in the bytes that follow it.
void CheckCountsAgainstSize(const PlyHeader& header, size_t data_size, const std::string& name) {
  // An ASCII file may omit the final newline.
  uint64_t remaining =
      data_size - header.data_offset + (header.encoding == PlyEncoding::kAscii ? 1 : 0);
  for (const PlyElement& element : header.elements) {
    const uint64_t each = MinInstanceBytes(element, header.encoding);
    if (each == 0) continue;
    if (element.count > remaining / each) {
      FailAtLine(name, element.line,
                 "element " + element.name + ": count " + std::to_string(element.count) +
                     " needs at least " + std::to_string(element.count) + " x " +
                     std::to_string(each) + " bytes but the file has only " +
                     std::to_string(data_size - header.data_offset) + " bytes of data");
    }
    remaining -= element.count * each;
  }
}

// ---------------------------------------------------------------------------------------------
// Value sources: the element loop is shared by the binary and ASCII encodings.

constexpr bool kHostBigEndian = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

template <typename U>
U ByteSwap(U u) {
  if constexpr (sizeof(U) == 1) {
    return u;
  } else if constexpr (sizeof(U) == 2) {
    return static_cast<U>(__builtin_bswap16(u));
  } else if constexpr (sizeof(U) == 4) {
    return static_cast<U>(__builtin_bswap32(u));
  } else {
    return static_cast<U>(__builtin_bswap64(u));
  }
}

// Where the reader is, for error messages ("vertex 12").
struct Position {
  const std::string* element = nullptr;
  uint64_t index = 0;
  std::string Describe() const { return *element + " " + std::to_string(index); }
};

class BinarySource {
 public:
  BinarySource(const std::string& name, std::string_view data, size_t offset, bool big_endian)
      : reader_(name, data.data(), data.size()), swap_(big_endian != kHostBigEndian) {
    reader_.Skip(offset, "header");
  }

  void BeginInstance() {}
  void EndInstance() {}

  double ReadNumber(PlyType t, const PlyProperty& p) {
    if (t == PlyType::kFloat32) return ReadFloat<float, uint32_t>(p);
    if (t == PlyType::kFloat64) return ReadFloat<double, uint64_t>(p);
    return static_cast<double>(ReadInteger(t, p));
  }

  // Integer types only (the header parser and slot assignment guarantee it).
  int64_t ReadInteger(PlyType t, const PlyProperty& p) {
    Need(TypeSize(t), p);
    switch (t) {
      case PlyType::kInt8:
        return static_cast<int8_t>(Raw<uint8_t>());
      case PlyType::kUint8:
        return Raw<uint8_t>();
      case PlyType::kInt16:
        return static_cast<int16_t>(Raw<uint16_t>());
      case PlyType::kUint16:
        return Raw<uint16_t>();
      case PlyType::kInt32:
        return static_cast<int32_t>(Raw<uint32_t>());
      case PlyType::kUint32:
        return Raw<uint32_t>();
      default:
        break;
    }
    Fail(p.name + ": not an integer type");
  }

  // Skips one scalar value, or `count` list items.
  void SkipValues(PlyType t, uint64_t count, const PlyProperty& p) {
    if (count > reader_.remaining() / TypeSize(t)) {
      Fail(p.name + ": truncated (" + std::to_string(count) + " values of " +
           std::to_string(TypeSize(t)) + " bytes, " + std::to_string(reader_.remaining()) +
           " bytes left)");
    }
    reader_.Skip(count * TypeSize(t), "");
  }

  // Largest list length that can still fit.
  uint64_t MaxListItems(PlyType item_type) const {
    return reader_.remaining() / TypeSize(item_type);
  }

  // Skips whole instances of an element made of scalars only.
  bool TrySkipFixedInstances(const PlyElement& element, uint64_t count) {
    uint64_t stride = 0;
    for (const PlyProperty& p : element.properties) {
      if (p.is_list) return false;
      stride += TypeSize(p.type);
    }
    if (stride != 0 && count > reader_.remaining() / stride) {
      Fail("element " + element.name + ": truncated (" + std::to_string(count) + " x " +
           std::to_string(stride) + " bytes, " + std::to_string(reader_.remaining()) + " left)");
    }
    reader_.Skip(count * stride, "");
    return true;
  }

  size_t TrailingBytes() const { return reader_.remaining(); }

  [[noreturn]] void Fail(const std::string& message) const {
    reader_.Fail((position_.element ? position_.Describe() + ": " : std::string()) + message);
  }

  Position position_;

 private:
  template <typename U>
  U Raw() {
    U u = reader_.Read<U>("value");
    return swap_ ? ByteSwap(u) : u;
  }
  // A float read as its bit pattern `Bits` (byte order fixed like an integer's).
  template <typename Float, typename Bits>
  Float ReadFloat(const PlyProperty& p) {
    static_assert(sizeof(Float) == sizeof(Bits));
    Need(sizeof(Float), p);
    const Bits bits = Raw<Bits>();
    Float value;
    std::memcpy(&value, &bits, sizeof(value));
    return value;
  }
  void Need(size_t bytes, const PlyProperty& p) const {
    if (reader_.remaining() < bytes) {
      Fail(p.name + ": truncated (needs " + std::to_string(bytes) + " bytes, " +
           std::to_string(reader_.remaining()) + " left)");
    }
  }

  BinaryReader reader_;
  bool swap_;
};

class AsciiSource {
 public:
  AsciiSource(const std::string& name, std::string_view data, int header_lines)
      : reader_(name, std::string(data)) {
    std::string_view skipped;
    for (int i = 0; i < header_lines; ++i) reader_.NextLine(&skipped);
  }

  void BeginInstance() {
    std::string_view line;
    if (!reader_.NextDataLine(&line, /*comment=*/0)) {
      Fail("unexpected end of file (the header announces more)");
    }
    fields_ = SplitFields(line);
    next_ = 0;
  }
  void EndInstance() {
    if (next_ != fields_.size()) {
      Fail(std::to_string(fields_.size()) + " values on the line, the header describes " +
           std::to_string(next_));
    }
  }

  double ReadNumber(PlyType t, const PlyProperty& p) {
    const std::string_view token = Next(p);
    if (IsIntegerType(t)) return static_cast<double>(ParseInteger(token, t, p));
    const double value = ParseReal(token, p);
    // A float property holds a float, as it would in a binary file.
    return t == PlyType::kFloat32 ? static_cast<double>(static_cast<float>(value)) : value;
  }

  int64_t ReadInteger(PlyType t, const PlyProperty& p) { return ParseInteger(Next(p), t, p); }

  void SkipValues(PlyType, uint64_t count, const PlyProperty& p) {
    if (count > fields_.size() - next_) {
      Fail(p.name + ": line ends after " + std::to_string(fields_.size()) + " values");
    }
    next_ += count;
  }

  uint64_t MaxListItems(PlyType) const { return fields_.size() - next_; }
  bool TrySkipFixedInstances(const PlyElement&, uint64_t) { return false; }

  size_t TrailingBytes() { return reader_.AtEnd() ? 0 : 1; }

  [[noreturn]] void Fail(const std::string& message) const {
    reader_.Fail((position_.element ? position_.Describe() + ": " : std::string()) + message);
  }

  Position position_;

 private:
  std::string_view Next(const PlyProperty& p) {
    if (next_ >= fields_.size()) {
      Fail(p.name + ": missing (the line has only " + std::to_string(fields_.size()) + " values)");
    }
    return fields_[next_++];
  }

  int64_t ParseInteger(std::string_view token, PlyType t, const PlyProperty& p) const {
    std::string_view digits = token;
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    int64_t value = 0;
    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec != std::errc() || ptr != digits.data() + digits.size()) {
      // Some writers print integers as "3.0"; accept integral reals.
      const double real = ParseReal(token, p);
      if (real != std::floor(real) || std::fabs(real) > 9.0e15) {
        Fail(p.name + ": '" + std::string(token) + "' is not an integer");
      }
      value = static_cast<int64_t>(real);
    }
    if (value < TypeMin(t) || value > TypeMax(t)) {
      Fail(p.name + ": " + std::to_string(value) + " is out of range for its type");
    }
    return value;
  }

  double ParseReal(std::string_view token, const PlyProperty& p) const {
    std::string_view digits = token;
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    double value = 0;
    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec == std::errc::result_out_of_range && ptr == digits.data() + digits.size()) {
      // Underflow reads as 0 (as strtod does), overflow as infinity (rejected where it matters).
      return std::strtod(std::string(digits).c_str(), nullptr);
    }
    if (ec != std::errc() || ptr != digits.data() + digits.size() || digits.empty()) {
      Fail(p.name + ": '" + std::string(token) + "' is not a number");
    }
    return value;
  }

  TextReader reader_;
  std::vector<std::string_view> fields_;
  size_t next_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Reading.

struct PlyWants {
  bool faces = false;
  bool normals = false;
  bool colors = false;
  bool scalars = false;
  int64_t max_vertices = INT64_MAX;  // meshes index vertices with int32
};

struct PlyData {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::array<uint8_t, 3>> colors;
  std::vector<float> scalars;
  std::vector<std::array<int32_t, 3>> triangles;
};

PlyProperty* FindProperty(PlyElement& element, std::initializer_list<const char*> names) {
  for (const char* n : names) {
    for (PlyProperty& p : element.properties) {
      if (p.name == n) return &p;
    }
  }
  return nullptr;
}

// Assigns slots for the properties we keep; leaves the rest kSkip. Returns false for a group
// (normals, colours) that is incomplete, which is then skipped.
bool AssignGroup(PlyElement& element,
                 const std::array<std::initializer_list<const char*>, 3>& names,
                 const std::array<Slot, 3>& slots) {
  std::array<PlyProperty*, 3> found{};
  for (int i = 0; i < 3; ++i) {
    found[i] = FindProperty(element, names[i]);
    if (found[i] == nullptr || found[i]->is_list) return false;
  }
  for (int i = 0; i < 3; ++i) found[i]->slot = slots[i];
  return true;
}

uint8_t ToColorByte(double v, PlyType t) {
  if (!std::isfinite(v)) return 0;
  if (t == PlyType::kFloat32 || t == PlyType::kFloat64) {
    v *= 255.0;  // floating colours are in [0, 1]
  } else if (t == PlyType::kInt16 || t == PlyType::kUint16) {
    v /= 257.0;  // 16-bit colours: 65535 -> 255
  }
  return static_cast<uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
}

// Which elements and properties the reader keeps: the slots assigned in the header.
struct PlyLayout {
  PlyElement* vertex = nullptr;
  PlyElement* face = nullptr;  // null when absent or not wanted
  bool has_normals = false, has_colors = false, has_scalars = false;
};

PlyLayout AssignSlots(PlyHeader& header, const PlyWants& wants, const std::string& name) {
  PlyLayout layout;
  PlyElement* face = nullptr;
  for (PlyElement& e : header.elements) {
    if (e.name == "vertex") layout.vertex = &e;
    if (e.name == "face") face = &e;
  }
  PlyElement* vertex = layout.vertex;
  if (vertex == nullptr) throw InputError(name + ": no 'vertex' element in the header");
  if (!AssignGroup(*vertex, {{{"x"}, {"y"}, {"z"}}}, {Slot::kX, Slot::kY, Slot::kZ})) {
    FailAtLine(name, vertex->line, "element vertex needs scalar properties x, y and z");
  }
  if (static_cast<int64_t>(std::min<uint64_t>(vertex->count, INT64_MAX)) > wants.max_vertices) {
    FailAtLine(name, vertex->line,
               "element vertex: " + std::to_string(vertex->count) +
                   " vertices are more than a mesh can index (" +
                   std::to_string(wants.max_vertices) + ")");
  }
  layout.has_normals =
      wants.normals &&
      AssignGroup(*vertex, {{{"nx", "normal_x"}, {"ny", "normal_y"}, {"nz", "normal_z"}}},
                  {Slot::kNx, Slot::kNy, Slot::kNz});
  layout.has_colors = wants.colors && AssignGroup(*vertex,
                                                  {{{"red", "diffuse_red", "r"},
                                                    {"green", "diffuse_green", "g"},
                                                    {"blue", "diffuse_blue", "b"}}},
                                                  {Slot::kRed, Slot::kGreen, Slot::kBlue});
  if (wants.scalars) {
    if (PlyProperty* q = FindProperty(*vertex, {"quality", "scalar"}); q && !q->is_list) {
      q->slot = Slot::kScalar;
      layout.has_scalars = true;
    }
  }
  if (wants.faces && face != nullptr) {
    PlyProperty* indices = FindProperty(*face, {"vertex_indices", "vertex_index"});
    if (indices == nullptr || !indices->is_list) {
      FailAtLine(name, face->line,
                 "element face has no list property vertex_indices (or vertex_index)");
    }
    if (!IsIntegerType(indices->type)) {
      FailAtLine(name, indices->line,
                 "face " + indices->name + ": index type must be an integer type");
    }
    indices->slot = Slot::kIndices;
    layout.face = face;
  }
  return layout;
}

// A list property: a face's indices (fanned into triangles) or a list skipped.
template <typename Source>
void ReadList(Source& source, const PlyProperty& p, int64_t num_vertices,
              std::vector<int64_t>* polygon, PlyData* out) {
  const int64_t n = source.ReadInteger(p.count_type, p);
  if (n < 0) source.Fail(p.name + ": negative list length " + std::to_string(n));
  if (static_cast<uint64_t>(n) > source.MaxListItems(p.type)) {
    source.Fail(p.name + ": list of " + std::to_string(n) + " items runs past the end of the data");
  }
  if (p.slot != Slot::kIndices) {
    source.SkipValues(p.type, static_cast<uint64_t>(n), p);
    return;
  }
  if (n < 3) {
    source.Fail(p.name + ": a face needs at least 3 vertices, this one has " + std::to_string(n));
  }
  polygon->resize(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) {
    const int64_t index = source.ReadInteger(p.type, p);
    if (index < 0 || index >= num_vertices) {
      source.Fail(p.name + ": vertex index " + std::to_string(index) + " is out of range [0, " +
                  std::to_string(num_vertices) + ")");
    }
    (*polygon)[static_cast<size_t>(k)] = index;
  }
  for (size_t k = 1; k + 1 < polygon->size(); ++k) {
    out->triangles.push_back({static_cast<int32_t>((*polygon)[0]),
                              static_cast<int32_t>((*polygon)[k]),
                              static_cast<int32_t>((*polygon)[k + 1])});
  }
}

// What one vertex instance holds.
struct PlyVertexValues {
  Eigen::Vector3d position, normal;
  std::array<uint8_t, 3> color{};
  float scalar = 0;
};

// One scalar property into its slot.
template <typename Source>
void ReadScalar(Source& source, const PlyProperty& p, PlyVertexValues* values) {
  if (p.slot == Slot::kSkip) {
    source.SkipValues(p.type, 1, p);
    return;
  }
  const double v = source.ReadNumber(p.type, p);
  switch (p.slot) {
    case Slot::kX:
    case Slot::kY:
    case Slot::kZ:
    case Slot::kNx:
    case Slot::kNy:
    case Slot::kNz:
      if (!std::isfinite(v)) source.Fail(p.name + ": value is not finite");
      if (p.slot <= Slot::kZ) {
        values->position[static_cast<int>(p.slot) - static_cast<int>(Slot::kX)] = v;
      } else {
        values->normal[static_cast<int>(p.slot) - static_cast<int>(Slot::kNx)] = v;
      }
      break;
    case Slot::kRed:
    case Slot::kGreen:
    case Slot::kBlue:
      values->color[static_cast<int>(p.slot) - static_cast<int>(Slot::kRed)] =
          ToColorByte(v, p.type);
      break;
    case Slot::kScalar:
      values->scalar = static_cast<float>(v);
      if (!std::isfinite(values->scalar)) source.Fail(p.name + ": value is not a finite float");
      break;
    default:
      break;
  }
}

template <typename Source>
void ReadElements(Source& source, PlyHeader& header, const PlyWants& wants, PlyData* out,
                  const std::string& name) {
  const PlyLayout layout = AssignSlots(header, wants, name);
  const PlyElement* vertex = layout.vertex;
  out->positions.reserve(vertex->count);
  if (layout.has_normals) out->normals.reserve(vertex->count);
  if (layout.has_colors) out->colors.reserve(vertex->count);
  if (layout.has_scalars) out->scalars.reserve(vertex->count);
  if (layout.face != nullptr) out->triangles.reserve(layout.face->count);
  const int64_t num_vertices = static_cast<int64_t>(vertex->count);

  std::vector<int64_t> polygon;
  for (PlyElement& element : header.elements) {
    source.position_.element = &element.name;
    source.position_.index = 0;
    if (element.properties.empty()) continue;
    const bool keep = &element == vertex || &element == layout.face;
    if (!keep && source.TrySkipFixedInstances(element, element.count)) continue;
    for (uint64_t i = 0; i < element.count; ++i) {
      source.position_.index = i;
      source.BeginInstance();
      PlyVertexValues values;
      for (const PlyProperty& p : element.properties) {
        if (p.is_list) {
          ReadList(source, p, num_vertices, &polygon, out);
        } else {
          ReadScalar(source, p, &values);
        }
      }
      source.EndInstance();
      if (&element == vertex) {
        out->positions.push_back(values.position);
        if (layout.has_normals) out->normals.push_back(values.normal);
        if (layout.has_colors) out->colors.push_back(values.color);
        if (layout.has_scalars) out->scalars.push_back(values.scalar);
      }
    }
  }
  source.position_.element = nullptr;
}

PlyData ParsePly(std::string_view data, const std::string& name, const PlyWants& wants) {
  PlyHeader header = ParseHeader(data, name);
  CheckCountsAgainstSize(header, data.size(), name);
  PlyData out;
  size_t trailing = 0;
  if (header.encoding == PlyEncoding::kAscii) {
    AsciiSource source(name, data, header.num_lines);
    ReadElements(source, header, wants, &out, name);
    trailing = source.TrailingBytes();
    if (trailing != 0) {
      throw InputError(name + ": data continues after the last element the header announces");
    }
  } else {
    BinarySource source(name, data, header.data_offset, header.encoding == PlyEncoding::kBinaryBig);
    ReadElements(source, header, wants, &out, name);
    trailing = source.TrailingBytes();
    // Some writers pad; the counts already matched, so a warning is enough.
    if (trailing != 0) spdlog::warn("{}: {} bytes after the last element ignored", name, trailing);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Writing.

template <typename T>
void AppendLittleEndian(std::string* out, T value) {
  static_assert(std::is_trivially_copyable_v<T>);
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (kHostBigEndian) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

void CheckFinite(const Eigen::Vector3d& v, const char* what, size_t i) {
  if (!v.allFinite()) {
    throw InternalError(std::string("writing PLY: ") + what + " " + std::to_string(i) +
                        " is not finite");
  }
}

void AppendCoordinate(std::string* out, double v, bool binary, bool as_float) {
  if (binary) {
    if (as_float) {
      AppendLittleEndian(out, static_cast<float>(v));
    } else {
      AppendLittleEndian(out, v);
    }
  } else if (as_float) {
    fmt::format_to(std::back_inserter(*out), "{}", static_cast<float>(v));
  } else {
    fmt::format_to(std::back_inserter(*out), "{}", v);  // shortest text that reads back exactly
  }
}

std::string HeaderStart(bool binary, const std::string& what) {
  return fmt::format("ply\nformat {} 1.0\ncomment written by manisweep {} ({})\n",
                     binary ? "binary_little_endian" : "ascii", MS_VERSION, what);
}

}  // namespace

Mesh ParsePlyMesh(std::string_view data, const std::string& name) {
  PlyWants wants;
  wants.faces = true;
  wants.colors = true;
  wants.max_vertices = INT32_MAX;
  PlyData ply = ParsePly(data, name, wants);
  Mesh mesh;
  mesh.vertices = std::move(ply.positions);
  mesh.faces = std::move(ply.triangles);
  mesh.vertex_colors = std::move(ply.colors);
  return mesh;
}

PointCloud ParsePlyPointCloud(std::string_view data, const std::string& name) {
  PlyWants wants;
  wants.normals = true;
  wants.colors = true;
  wants.scalars = true;
  PlyData ply = ParsePly(data, name, wants);
  PointCloud cloud;
  cloud.points = std::move(ply.positions);
  cloud.normals = std::move(ply.normals);
  cloud.colors = std::move(ply.colors);
  cloud.scalars = std::move(ply.scalars);
  return cloud;
}

std::string FormatPlyMesh(const Mesh& mesh, const MeshWriteOptions& options) {
  const size_t nv = mesh.vertices.size();
  if (mesh.HasColors() && mesh.vertex_colors.size() != nv) {
    throw InternalError("writing PLY: " + std::to_string(mesh.vertex_colors.size()) +
                        " vertex colours for " + std::to_string(nv) + " vertices");
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int32_t v : mesh.faces[f]) {
      if (v < 0 || static_cast<size_t>(v) >= nv) {
        throw InternalError("writing PLY: face " + std::to_string(f) + " has vertex index " +
                            std::to_string(v) + " out of range [0, " + std::to_string(nv) + ")");
      }
    }
  }
  const bool binary = options.binary;
  const char* coord_type = options.float_coordinates ? "float" : "double";
  std::string out = HeaderStart(binary, "mesh");
  fmt::format_to(std::back_inserter(out), "element vertex {}\n", nv);
  for (const char* axis : {"x", "y", "z"}) {
    fmt::format_to(std::back_inserter(out), "property {} {}\n", coord_type, axis);
  }
  if (mesh.HasColors()) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  fmt::format_to(std::back_inserter(out),
                 "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
                 mesh.faces.size());
  const size_t vertex_bytes = binary ? (options.float_coordinates ? 12 : 24) + 3 : 64;
  out.reserve(out.size() + nv * vertex_bytes + mesh.faces.size() * (binary ? 13 : 32));
  for (size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3d& p = mesh.vertices[i];
    CheckFinite(p, "vertex", i);
    for (int k = 0; k < 3; ++k) {
      if (!binary && k > 0) out += ' ';
      AppendCoordinate(&out, p[k], binary, options.float_coordinates);
    }
    if (mesh.HasColors()) {
      const auto& c = mesh.vertex_colors[i];
      if (binary) {
        out.append(reinterpret_cast<const char*>(c.data()), 3);
      } else {
        fmt::format_to(std::back_inserter(out), " {} {} {}", c[0], c[1], c[2]);
      }
    }
    if (!binary) out += '\n';
  }
  for (const auto& f : mesh.faces) {
    if (binary) {
      out += static_cast<char>(3);
      for (int32_t v : f) AppendLittleEndian(&out, v);
    } else {
      fmt::format_to(std::back_inserter(out), "3 {} {} {}\n", f[0], f[1], f[2]);
    }
  }
  return out;
}

std::string FormatPlyPointCloud(const PointCloud& cloud, const MeshWriteOptions& options) {
  const size_t n = cloud.points.size();
  auto check_size = [n](size_t size, const char* what) {
    if (size != 0 && size != n) {
      throw InternalError("writing PLY: " + std::to_string(size) + " " + what + " for " +
                          std::to_string(n) + " points");
    }
  };
  check_size(cloud.normals.size(), "normals");
  check_size(cloud.colors.size(), "colours");
  check_size(cloud.scalars.size(), "scalars");
  const bool normals = !cloud.normals.empty();
  const bool colors = !cloud.colors.empty();
  const bool scalars = !cloud.scalars.empty();
  const bool binary = options.binary;
  const char* coord_type = options.float_coordinates ? "float" : "double";
  std::string out = HeaderStart(binary, "points");
  fmt::format_to(std::back_inserter(out), "element vertex {}\n", n);
  for (const char* axis : {"x", "y", "z"}) {
    fmt::format_to(std::back_inserter(out), "property {} {}\n", coord_type, axis);
  }
  if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (scalars) out += "property float quality\n";
  out += "end_header\n";
  for (size_t i = 0; i < n; ++i) {
    CheckFinite(cloud.points[i], "point", i);
    for (int k = 0; k < 3; ++k) {
      if (!binary && k > 0) out += ' ';
      AppendCoordinate(&out, cloud.points[i][k], binary, options.float_coordinates);
    }
    if (normals) {
      CheckFinite(cloud.normals[i], "normal", i);
      for (int k = 0; k < 3; ++k) {
        if (!binary) out += ' ';
        AppendCoordinate(&out, cloud.normals[i][k], binary, /*as_float=*/true);
      }
    }
    if (colors) {
      const auto& c = cloud.colors[i];
      if (binary) {
        out.append(reinterpret_cast<const char*>(c.data()), 3);
      } else {
        fmt::format_to(std::back_inserter(out), " {} {} {}", c[0], c[1], c[2]);
      }
    }
    if (scalars) {
      if (!std::isfinite(cloud.scalars[i])) {
        throw InternalError("writing PLY: scalar " + std::to_string(i) + " is not finite");
      }
      if (binary) {
        AppendLittleEndian(&out, cloud.scalars[i]);
      } else {
        fmt::format_to(std::back_inserter(out), " {}", cloud.scalars[i]);
      }
    }
    if (!binary) out += '\n';
  }
  return out;
}

}  // namespace ms
