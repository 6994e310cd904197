#include "gl/objects.h"

#include <fmt/format.h>

#include <cctype>
#include <utility>

#include "base/check.h"
#include "base/error.h"
#include "gl/gl_api.h"
#include "shaders/shaders.h"

static_assert(sizeof(GLuint) == sizeof(uint32_t), "ids are exchanged as uint32_t");

namespace ms::gl {
namespace {

GLenum StageEnum(ShaderStage stage) {
  switch (stage) {
    case ShaderStage::kVertex:
      return GL_VERTEX_SHADER;
    case ShaderStage::kGeometry:
      return GL_GEOMETRY_SHADER;
    case ShaderStage::kFragment:
      return GL_FRAGMENT_SHADER;
    case ShaderStage::kCompute:
      return GL_COMPUTE_SHADER;
  }
  return GL_VERTEX_SHADER;
}

std::vector<std::string_view> SplitLines(std::string_view text) {
  std::vector<std::string_view> lines;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    lines.push_back(text.substr(pos, end - pos));
    pos = end + 1;
  }
  return lines;
}

// Parses the location at the start of a compiler message: Mesa "0:12(5): ...", NVIDIA
// "0(12) : ...". Returns false if the line has none.
bool ParseLogLocation(std::string_view line, int* string_number, int* line_number) {
  size_t i = 0;
  auto number = [&](int* out) {
    const size_t start = i;
    int value = 0;
    while (i < line.size() && std::isdigit(static_cast<unsigned char>(line[i])) && i - start < 7) {
      value = value * 10 + (line[i++] - '0');
    }
    *out = value;
    return i > start;
  };
  if (!number(string_number) || i >= line.size() || (line[i] != ':' && line[i] != '(')) {
    return false;
  }
  ++i;
  return number(line_number);
}

// The driver's log with each located message followed by "    > <source line>".
std::string AnnotateLog(const std::string& log, const ShaderSource& source) {
  std::string out;
  for (std::string_view line : SplitLines(log)) {
    if (line.empty()) continue;
    out += "  ";
    out += line;
    out += '\n';
    int string_number = 0, line_number = 0;
    if (!ParseLogLocation(line, &string_number, &line_number) || line_number < 1) continue;
    std::string file = source.name;
    std::string_view text = source.text;
    if (string_number > 0 && string_number < static_cast<int>(source.included_names.size())) {
      file = source.included_names[string_number];
      if (!shaders::Has(file)) continue;
      text = shaders::Source(file);
    } else if (string_number == 0 && shaders::Has(source.name)) {
      text = shaders::Source(source.name);  // numbering follows the file (see #line)
    } else if (string_number != 0) {
      continue;
    }
    const std::vector<std::string_view> lines = SplitLines(text);
    if (line_number <= static_cast<int>(lines.size())) {
      out += fmt::format("    > {}:{}: {}\n", file, line_number, lines[line_number - 1]);
    }
  }
  return out;
}

GLenum UsageEnum(BufferUsage usage) {
  switch (usage) {
    case BufferUsage::kStaticDraw:
      return GL_STATIC_DRAW;
    case BufferUsage::kDynamicDraw:
      return GL_DYNAMIC_DRAW;
    case BufferUsage::kStreamDraw:
      return GL_STREAM_DRAW;
    case BufferUsage::kStaticRead:
      return GL_STATIC_READ;
    case BufferUsage::kDynamicRead:
      return GL_DYNAMIC_READ;
    case BufferUsage::kDynamicCopy:
      return GL_DYNAMIC_COPY;
  }
  return GL_STATIC_DRAW;
}

struct FormatInfo {
  GLenum internal_format;
  GLenum pixel_format;  // for glTexSubImage / glReadPixels
  GLenum pixel_type;
  int cv_type;
  int bytes_per_pixel;
};

FormatInfo Info(TextureFormat format) {
  switch (format) {
    case TextureFormat::kR8:
      return {GL_R8, GL_RED, GL_UNSIGNED_BYTE, CV_8UC1, 1};
    case TextureFormat::kRGBA8:
      return {GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, CV_8UC4, 4};
    case TextureFormat::kR32F:
      return {GL_R32F, GL_RED, GL_FLOAT, CV_32FC1, 4};
    case TextureFormat::kRG32F:
      return {GL_RG32F, GL_RG, GL_FLOAT, CV_32FC2, 8};
    case TextureFormat::kRGBA32F:
      return {GL_RGBA32F, GL_RGBA, GL_FLOAT, CV_32FC4, 16};
    case TextureFormat::kR32I:
      return {GL_R32I, GL_RED_INTEGER, GL_INT, CV_32SC1, 4};
    case TextureFormat::kR32UI:
      return {GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, CV_32SC1, 4};
    case TextureFormat::kDepth32F:
      return {GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT, GL_FLOAT, CV_32FC1, 4};
  }
  return {GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, CV_8UC4, 4};
}

void CheckImage(const cv::Mat& image, TextureFormat format, const char* what) {
  if (image.type() != CvTypeOf(format)) {
    throw InternalError(fmt::format("{}: cv::Mat type {} does not match texture format {}", what,
                                    image.type(), TextureFormatName(format)));
  }
}

// Pixel-store state for tightly packed cv::Mat rows (any row stride, any alignment).
void SetUnpackRows(const cv::Mat& image) {
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, static_cast<GLint>(image.step[0] / image.elemSize()));
}

void ResetUnpackRows() {
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
}

void ApplyFilter(GLenum target, TextureFilter filter) {
  const GLenum min = filter == TextureFilter::kNearest  ? GL_NEAREST
                     : filter == TextureFilter::kLinear ? GL_LINEAR
                                                        : GL_LINEAR_MIPMAP_LINEAR;
  const GLenum mag = filter == TextureFilter::kNearest ? GL_NEAREST : GL_LINEAR;
  glTexParameteri(target, GL_TEXTURE_MIN_FILTER, min);
  glTexParameteri(target, GL_TEXTURE_MAG_FILTER, mag);
}

void ApplyWrap(GLenum target, TextureWrap wrap) {
  const GLenum mode = wrap == TextureWrap::kRepeat          ? GL_REPEAT
                      : wrap == TextureWrap::kClampToBorder ? GL_CLAMP_TO_BORDER
                                                            : GL_CLAMP_TO_EDGE;
  glTexParameteri(target, GL_TEXTURE_WRAP_S, mode);
  glTexParameteri(target, GL_TEXTURE_WRAP_T, mode);
  const float border[4] = {0, 0, 0, 0};
  glTexParameterfv(target, GL_TEXTURE_BORDER_COLOR, border);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string ShaderStageName(ShaderStage stage) {
  switch (stage) {
    case ShaderStage::kVertex:
      return "vertex";
    case ShaderStage::kGeometry:
      return "geometry";
    case ShaderStage::kFragment:
      return "fragment";
    case ShaderStage::kCompute:
      return "compute";
  }
  return "unknown";
}

ShaderStage ShaderStageFromName(const std::string& file_name) {
  auto ends_with = [&](const char* suffix) {
    const size_t n = std::char_traits<char>::length(suffix);
    return file_name.size() >= n && file_name.compare(file_name.size() - n, n, suffix) == 0;
  };
  if (ends_with(".vert")) return ShaderStage::kVertex;
  if (ends_with(".geom")) return ShaderStage::kGeometry;
  if (ends_with(".frag")) return ShaderStage::kFragment;
  if (ends_with(".comp")) return ShaderStage::kCompute;
  throw InternalError("shader '" + file_name +
                      "': cannot tell the stage (expected .vert, .geom, .frag or .comp)");
}

ShaderProgram::ShaderProgram(std::string name, const std::vector<ShaderSource>& sources)
    : name_(std::move(name)) {
  if (sources.empty()) throw InternalError(name_ + ": a program needs at least one shader");
  std::vector<GLuint> shaders;
  auto cleanup = [&] {
    for (GLuint s : shaders) glDeleteShader(s);
  };
  for (const ShaderSource& source : sources) {
    const GLuint shader = glCreateShader(StageEnum(source.stage));
    if (shader == 0) {
      cleanup();
      throw InternalError(name_ + ": glCreateShader failed for " + source.name +
                          " (no current GL context?)");
    }
    shaders.push_back(shader);
    const char* text = source.text.c_str();
    const GLint length = static_cast<GLint>(source.text.size());
    glShaderSource(shader, 1, &text, &length);
    glCompileShader(shader);
    GLint ok = 0, log_length = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &log_length);
    std::string log(std::max(log_length, 1), '\0');
    glGetShaderInfoLog(shader, log_length, nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    if (!ok) {
      cleanup();
      throw InternalError(name_ + ": " + source.name + " (" + ShaderStageName(source.stage) +
                          " shader) failed to compile:\n" + AnnotateLog(log, source));
    }
  }
  id_ = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(id_, s);
  glLinkProgram(id_);
  cleanup();  // flagged for deletion; freed with the program
  GLint ok = 0, log_length = 0;
  glGetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (!ok) {
    glGetProgramiv(id_, GL_INFO_LOG_LENGTH, &log_length);
    std::string log(std::max(log_length, 1), '\0');
    glGetProgramInfoLog(id_, log_length, nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    Release();
    throw InternalError(name_ + ": failed to link:\n" + log);
  }
  CheckGlError(("linking " + name_).c_str());
}

ShaderProgram ShaderProgram::FromEmbedded(const std::vector<std::string>& names,
                                          const std::vector<std::string>& defines) {
  std::vector<ShaderSource> sources;
  std::string program_name;
  for (const std::string& name : names) {
    ShaderSource source;
    source.stage = ShaderStageFromName(name);
    source.name = name;
    source.text = InsertDefines(shaders::Expand(name, &source.included_names), defines);
    sources.push_back(std::move(source));
    program_name += (program_name.empty() ? "" : "+") + name;
  }
  return ShaderProgram(program_name, sources);
}

ShaderProgram::~ShaderProgram() { Release(); }

ShaderProgram::ShaderProgram(ShaderProgram&& o) noexcept
    : id_(std::exchange(o.id_, 0)),
      name_(std::move(o.name_)),
      locations_(std::move(o.locations_)) {}

ShaderProgram& ShaderProgram::operator=(ShaderProgram&& o) noexcept {
  if (this != &o) {
    Release();
    id_ = std::exchange(o.id_, 0);
    name_ = std::move(o.name_);
    locations_ = std::move(o.locations_);
  }
  return *this;
}

void ShaderProgram::Release() {
  if (id_ != 0) glDeleteProgram(id_);
  id_ = 0;
}

void ShaderProgram::Use() const { glUseProgram(id_); }

int ShaderProgram::Location(const std::string& uniform) const {
  auto it = locations_.find(uniform);
  if (it != locations_.end()) return it->second;
  const int location = glGetUniformLocation(id_, uniform.c_str());
  locations_.emplace(uniform, location);
  return location;
}

void ShaderProgram::Set(const std::string& u, int v) const {
  glProgramUniform1i(id_, Location(u), v);
}
void ShaderProgram::Set(const std::string& u, uint32_t v) const {
  glProgramUniform1ui(id_, Location(u), v);
}
void ShaderProgram::Set(const std::string& u, float v) const {
  glProgramUniform1f(id_, Location(u), v);
}
void ShaderProgram::Set(const std::string& u, const Eigen::Vector2f& v) const {
  glProgramUniform2f(id_, Location(u), v.x(), v.y());
}
void ShaderProgram::Set(const std::string& u, const Eigen::Vector3f& v) const {
  glProgramUniform3f(id_, Location(u), v.x(), v.y(), v.z());
}
void ShaderProgram::Set(const std::string& u, const Eigen::Vector4f& v) const {
  glProgramUniform4f(id_, Location(u), v.x(), v.y(), v.z(), v.w());
}
void ShaderProgram::Set(const std::string& u, const Eigen::Vector2i& v) const {
  glProgramUniform2i(id_, Location(u), v.x(), v.y());
}
void ShaderProgram::Set(const std::string& u, const Eigen::Matrix3f& m) const {
  glProgramUniformMatrix3fv(id_, Location(u), 1, GL_FALSE, m.data());  // Eigen: column-major
}
void ShaderProgram::Set(const std::string& u, const Eigen::Matrix4f& m) const {
  glProgramUniformMatrix4fv(id_, Location(u), 1, GL_FALSE, m.data());
}
void ShaderProgram::Set(const std::string& u, const std::vector<float>& values) const {
  glProgramUniform1fv(id_, Location(u), static_cast<GLsizei>(values.size()), values.data());
}

void ShaderProgram::Dispatch(int x, int y, int z) const {
  MS_CHECK(x >= 1 && y >= 1 && z >= 1) << name_ << ": empty dispatch " << x << "x" << y << "x" << z;
  Use();
  glDispatchCompute(static_cast<GLuint>(x), static_cast<GLuint>(y), static_cast<GLuint>(z));
}

Eigen::Vector3i ShaderProgram::WorkGroupSize() const {
  GLint size[3] = {0, 0, 0};
  glGetProgramiv(id_, GL_COMPUTE_WORK_GROUP_SIZE, size);
  CheckGlError((name_ + ": work group size (not a compute program?)").c_str());
  return {size[0], size[1], size[2]};
}

void MemoryBarrier() { glMemoryBarrier(GL_ALL_BARRIER_BITS); }
void Finish() { glFinish(); }

// ---------------------------------------------------------------------------------------------

Buffer::Buffer() { glGenBuffers(1, &id_); }

Buffer::Buffer(size_t bytes, const void* data, BufferUsage usage) : Buffer() {
  Allocate(bytes, data, usage);
}

Buffer::~Buffer() { Release(); }
Buffer::Buffer(Buffer&& o) noexcept
    : id_(std::exchange(o.id_, 0)), size_(std::exchange(o.size_, 0)) {}
Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    Release();
    id_ = std::exchange(o.id_, 0);
    size_ = std::exchange(o.size_, 0);
  }
  return *this;
}
void Buffer::Release() {
  if (id_ != 0) glDeleteBuffers(1, &id_);
  id_ = 0;
}

void Buffer::Allocate(size_t bytes, const void* data, BufferUsage usage) {
  glBindBuffer(GL_COPY_WRITE_BUFFER, id_);
  glBufferData(GL_COPY_WRITE_BUFFER, static_cast<GLsizeiptr>(bytes), data, UsageEnum(usage));
  size_ = bytes;
  CheckGlError(fmt::format("allocating a {}-byte buffer", bytes).c_str());
}

void Buffer::Upload(size_t offset, size_t bytes, const void* data) {
  MS_CHECK(offset + bytes <= size_)
      << "buffer upload past the end: " << offset << "+" << bytes << " > " << size_;
  if (bytes == 0) return;
  glBindBuffer(GL_COPY_WRITE_BUFFER, id_);
  glBufferSubData(GL_COPY_WRITE_BUFFER, static_cast<GLintptr>(offset),
                  static_cast<GLsizeiptr>(bytes), data);
}

void Buffer::Download(size_t offset, size_t bytes, void* out) const {
  MS_CHECK(offset + bytes <= size_)
      << "buffer download past the end: " << offset << "+" << bytes << " > " << size_;
  if (bytes == 0) return;
  glBindBuffer(GL_COPY_READ_BUFFER, id_);
  glGetBufferSubData(GL_COPY_READ_BUFFER, static_cast<GLintptr>(offset),
                     static_cast<GLsizeiptr>(bytes), out);
  CheckGlError("buffer download");
}

void Buffer::Fill(uint32_t value) {
  glBindBuffer(GL_COPY_WRITE_BUFFER, id_);
  glClearBufferData(GL_COPY_WRITE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &value);
}

void Buffer::BindStorage(int binding) const {
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(binding), id_);
}
void Buffer::BindUniformBlock(int binding) const {
  glBindBufferBase(GL_UNIFORM_BUFFER, static_cast<GLuint>(binding), id_);
}
void Buffer::BindAtomicCounter(int binding) const {
  glBindBufferBase(GL_ATOMIC_COUNTER_BUFFER, static_cast<GLuint>(binding), id_);
}

// ---------------------------------------------------------------------------------------------

VertexArray::VertexArray() { glGenVertexArrays(1, &id_); }
VertexArray::~VertexArray() { Release(); }
VertexArray::VertexArray(VertexArray&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
VertexArray& VertexArray::operator=(VertexArray&& o) noexcept {
  if (this != &o) {
    Release();
    id_ = std::exchange(o.id_, 0);
  }
  return *this;
}
void VertexArray::Release() {
  if (id_ != 0) glDeleteVertexArrays(1, &id_);
  id_ = 0;
}

void VertexArray::SetFloatAttribute(int location, const Buffer& buffer, int components,
                                    size_t stride, size_t offset) {
  glBindVertexArray(id_);
  glBindBuffer(GL_ARRAY_BUFFER, buffer.id());
  glEnableVertexAttribArray(static_cast<GLuint>(location));
  glVertexAttribPointer(static_cast<GLuint>(location), components, GL_FLOAT, GL_FALSE,
                        static_cast<GLsizei>(stride), reinterpret_cast<const void*>(offset));
  glBindVertexArray(0);
}

void VertexArray::SetIntAttribute(int location, const Buffer& buffer, int components, size_t stride,
                                  size_t offset) {
  glBindVertexArray(id_);
  glBindBuffer(GL_ARRAY_BUFFER, buffer.id());
  glEnableVertexAttribArray(static_cast<GLuint>(location));
  glVertexAttribIPointer(static_cast<GLuint>(location), components, GL_INT,
                         static_cast<GLsizei>(stride), reinterpret_cast<const void*>(offset));
  glBindVertexArray(0);
}

void VertexArray::SetIndexBuffer(const Buffer& buffer) {
  glBindVertexArray(id_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffer.id());  // recorded in the VAO
  glBindVertexArray(0);
}

void VertexArray::Bind() const { glBindVertexArray(id_); }

void VertexArray::DrawIndexedTriangles(size_t index_count, size_t first_index) const {
  Bind();
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(index_count), GL_UNSIGNED_INT,
                 reinterpret_cast<const void*>(first_index * sizeof(uint32_t)));
}

void VertexArray::DrawTriangles(size_t vertex_count, size_t first_vertex) const {
  Bind();
  glDrawArrays(GL_TRIANGLES, static_cast<GLint>(first_vertex), static_cast<GLsizei>(vertex_count));
}

void VertexArray::DrawPoints(size_t vertex_count, size_t first_vertex) const {
  Bind();
  glDrawArrays(GL_POINTS, static_cast<GLint>(first_vertex), static_cast<GLsizei>(vertex_count));
}

// ---------------------------------------------------------------------------------------------

int CvTypeOf(TextureFormat format) { return Info(format).cv_type; }

std::string TextureFormatName(TextureFormat format) {
  switch (format) {
    case TextureFormat::kR8:
      return "R8";
    case TextureFormat::kRGBA8:
      return "RGBA8";
    case TextureFormat::kR32F:
      return "R32F";
    case TextureFormat::kRG32F:
      return "RG32F";
    case TextureFormat::kRGBA32F:
      return "RGBA32F";
    case TextureFormat::kR32I:
      return "R32I";
    case TextureFormat::kR32UI:
      return "R32UI";
    case TextureFormat::kDepth32F:
      return "DEPTH32F";
  }
  return "unknown";
}

bool IsIntegerFormat(TextureFormat format) {
  return format == TextureFormat::kR32I || format == TextureFormat::kR32UI;
}

Texture2D::Texture2D(int width, int height, TextureFormat format, int levels)
    : width_(width), height_(height), levels_(levels), format_(format) {
  MS_CHECK(width > 0 && height > 0 && levels >= 1)
      << "texture size " << width << "x" << height << " levels " << levels;
  glGenTextures(1, &id_);
  glBindTexture(GL_TEXTURE_2D, id_);
  glTexStorage2D(GL_TEXTURE_2D, levels, Info(format).internal_format, width, height);
  ApplyFilter(GL_TEXTURE_2D, TextureFilter::kNearest);
  ApplyWrap(GL_TEXTURE_2D, TextureWrap::kClampToEdge);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, levels - 1);
  CheckGlError(
      fmt::format("creating a {}x{} {} texture", width, height, TextureFormatName(format)).c_str());
}

Texture2D::~Texture2D() { Release(); }
Texture2D::Texture2D(Texture2D&& o) noexcept
    : id_(std::exchange(o.id_, 0)),
      width_(o.width_),
      height_(o.height_),
      levels_(o.levels_),
      format_(o.format_) {}
Texture2D& Texture2D::operator=(Texture2D&& o) noexcept {
  if (this != &o) {
    Release();
    id_ = std::exchange(o.id_, 0);
    width_ = o.width_;
    height_ = o.height_;
    levels_ = o.levels_;
    format_ = o.format_;
  }
  return *this;
}
void Texture2D::Release() {
  if (id_ != 0) glDeleteTextures(1, &id_);
  id_ = 0;
}

void Texture2D::Upload(const cv::Mat& image, int level) { UploadRect(0, 0, image, level); }

void Texture2D::UploadRect(int x, int y, const cv::Mat& image, int level) {
  CheckImage(image, format_, "texture upload");
  const int w = std::max(1, width_ >> level), h = std::max(1, height_ >> level);
  MS_CHECK(level >= 0 && level < levels_ && x >= 0 && y >= 0 && x + image.cols <= w &&
           y + image.rows <= h)
      << "texture upload of " << image.cols << "x" << image.rows << " at " << x << "," << y
      << " outside level " << level << " (" << w << "x" << h << ")";
  const FormatInfo info = Info(format_);
  glBindTexture(GL_TEXTURE_2D, id_);
  SetUnpackRows(image);
  glTexSubImage2D(GL_TEXTURE_2D, level, x, y, image.cols, image.rows, info.pixel_format,
                  info.pixel_type, image.data);
  ResetUnpackRows();
  CheckGlError("texture upload");
}

cv::Mat Texture2D::Download(int level) const {
  MS_CHECK(level >= 0 && level < levels_) << "texture level " << level;
  const int w = std::max(1, width_ >> level), h = std::max(1, height_ >> level);
  const FormatInfo info = Info(format_);
  cv::Mat out(h, w, info.cv_type);
  glBindTexture(GL_TEXTURE_2D, id_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTexImage(GL_TEXTURE_2D, level, info.pixel_format, info.pixel_type, out.data);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  CheckGlError("texture download");
  return out;
}

void Texture2D::GenerateMipmaps() {
  glBindTexture(GL_TEXTURE_2D, id_);
  glGenerateMipmap(GL_TEXTURE_2D);
}
void Texture2D::SetFilter(TextureFilter filter) {
  glBindTexture(GL_TEXTURE_2D, id_);
  ApplyFilter(GL_TEXTURE_2D, filter);
}
void Texture2D::SetWrap(TextureWrap wrap) {
  glBindTexture(GL_TEXTURE_2D, id_);
  ApplyWrap(GL_TEXTURE_2D, wrap);
}
void Texture2D::Bind(int unit) const {
  glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
  glBindTexture(GL_TEXTURE_2D, id_);
}
void Texture2D::BindImage(int unit, ImageAccess access, int level) const {
  const GLenum mode = access == ImageAccess::kReadOnly    ? GL_READ_ONLY
                      : access == ImageAccess::kWriteOnly ? GL_WRITE_ONLY
                                                          : GL_READ_WRITE;
  glBindImageTexture(static_cast<GLuint>(unit), id_, level, GL_FALSE, 0, mode,
                     Info(format_).internal_format);
}

Texture2DArray::Texture2DArray(int width, int height, int layers, TextureFormat format, int levels)
    : width_(width), height_(height), layers_(layers), levels_(levels), format_(format) {
  MS_CHECK(width > 0 && height > 0 && layers > 0 && levels >= 1)
      << "texture array " << width << "x" << height << "x" << layers;
  glGenTextures(1, &id_);
  glBindTexture(GL_TEXTURE_2D_ARRAY, id_);
  glTexStorage3D(GL_TEXTURE_2D_ARRAY, levels, Info(format).internal_format, width, height, layers);
  ApplyFilter(GL_TEXTURE_2D_ARRAY, TextureFilter::kNearest);
  ApplyWrap(GL_TEXTURE_2D_ARRAY, TextureWrap::kClampToEdge);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, levels - 1);
  CheckGlError("creating a texture array");
}
Texture2DArray::~Texture2DArray() { Release(); }
Texture2DArray::Texture2DArray(Texture2DArray&& o) noexcept
    : id_(std::exchange(o.id_, 0)),
      width_(o.width_),
      height_(o.height_),
      layers_(o.layers_),
      levels_(o.levels_),
      format_(o.format_) {}
Texture2DArray& Texture2DArray::operator=(Texture2DArray&& o) noexcept {
  if (this != &o) {
    Release();
    id_ = std::exchange(o.id_, 0);
    width_ = o.width_;
    height_ = o.height_;
    layers_ = o.layers_;
    levels_ = o.levels_;
    format_ = o.format_;
  }
  return *this;
}
void Texture2DArray::Release() {
  if (id_ != 0) glDeleteTextures(1, &id_);
  id_ = 0;
}

void Texture2DArray::UploadLayer(int layer, const cv::Mat& image, int level) {
  CheckImage(image, format_, "texture array upload");
  const int w = std::max(1, width_ >> level), h = std::max(1, height_ >> level);
  MS_CHECK(layer >= 0 && layer < layers_ && image.cols == w && image.rows == h)
      << "texture array layer " << layer << " upload of " << image.cols << "x" << image.rows;
  const FormatInfo info = Info(format_);
  glBindTexture(GL_TEXTURE_2D_ARRAY, id_);
  SetUnpackRows(image);
  glTexSubImage3D(GL_TEXTURE_2D_ARRAY, level, 0, 0, layer, w, h, 1, info.pixel_format,
                  info.pixel_type, image.data);
  ResetUnpackRows();
  CheckGlError("texture array upload");
}
void Texture2DArray::GenerateMipmaps() {
  glBindTexture(GL_TEXTURE_2D_ARRAY, id_);
  glGenerateMipmap(GL_TEXTURE_2D_ARRAY);
}
void Texture2DArray::SetFilter(TextureFilter filter) {
  glBindTexture(GL_TEXTURE_2D_ARRAY, id_);
  ApplyFilter(GL_TEXTURE_2D_ARRAY, filter);
}
void Texture2DArray::SetWrap(TextureWrap wrap) {
  glBindTexture(GL_TEXTURE_2D_ARRAY, id_);
  ApplyWrap(GL_TEXTURE_2D_ARRAY, wrap);
}
void Texture2DArray::Bind(int unit) const {
  glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(unit));
  glBindTexture(GL_TEXTURE_2D_ARRAY, id_);
}

// ---------------------------------------------------------------------------------------------

Framebuffer::Framebuffer(int width, int height, const std::vector<TextureFormat>& color_formats,
                         bool with_depth)
    : width_(width), height_(height) {
  GLint max_attachments = 0;
  glGetIntegerv(GL_MAX_COLOR_ATTACHMENTS, &max_attachments);
  MS_CHECK(static_cast<int>(color_formats.size()) <= max_attachments)
      << color_formats.size() << " colour attachments, the driver allows " << max_attachments;
  glGenFramebuffers(1, &id_);
  glBindFramebuffer(GL_FRAMEBUFFER, id_);
  for (size_t i = 0; i < color_formats.size(); ++i) {
    MS_CHECK(color_formats[i] != TextureFormat::kDepth32F) << "depth format as colour attachment";
    colors_.emplace_back(width, height, color_formats[i]);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i),
                           GL_TEXTURE_2D, colors_.back().id(), 0);
  }
  if (with_depth) {
    depth_.emplace_back(width, height, TextureFormat::kDepth32F);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_.back().id(),
                           0);
  }
  Bind();
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    Release();
    throw InternalError(
        fmt::format("{}x{} framebuffer incomplete (status 0x{:x})", width, height, status));
  }
  CheckGlError("creating a framebuffer");
}

Framebuffer::~Framebuffer() { Release(); }
Framebuffer::Framebuffer(Framebuffer&& o) noexcept
    : id_(std::exchange(o.id_, 0)),
      width_(o.width_),
      height_(o.height_),
      colors_(std::move(o.colors_)),
      depth_(std::move(o.depth_)) {}
Framebuffer& Framebuffer::operator=(Framebuffer&& o) noexcept {
  if (this != &o) {
    Release();
    id_ = std::exchange(o.id_, 0);
    width_ = o.width_;
    height_ = o.height_;
    colors_ = std::move(o.colors_);
    depth_ = std::move(o.depth_);
  }
  return *this;
}
void Framebuffer::Release() {
  if (id_ != 0) glDeleteFramebuffers(1, &id_);
  id_ = 0;
}

void Framebuffer::Bind() const {
  glBindFramebuffer(GL_FRAMEBUFFER, id_);
  glViewport(0, 0, width_, height_);
  std::vector<GLenum> buffers;
  for (size_t i = 0; i < colors_.size(); ++i) buffers.push_back(GL_COLOR_ATTACHMENT0 + i);
  if (buffers.empty()) {
    glDrawBuffer(GL_NONE);
  } else {
    glDrawBuffers(static_cast<GLsizei>(buffers.size()), buffers.data());
  }
}

void Framebuffer::BindDefault() { glBindFramebuffer(GL_FRAMEBUFFER, 0); }

const Texture2D& Framebuffer::color(int attachment) const {
  MS_CHECK(attachment >= 0 && attachment < num_colors()) << "attachment " << attachment;
  return colors_[attachment];
}

void Framebuffer::Clear(int attachment, const Eigen::Vector4f& value) const {
  MS_CHECK(!IsIntegerFormat(color(attachment).format())) << "Clear on an integer attachment";
  glBindFramebuffer(GL_FRAMEBUFFER, id_);
  glClearBufferfv(GL_COLOR, attachment, value.data());
}

void Framebuffer::ClearInt(int attachment, const Eigen::Vector4i& value) const {
  glBindFramebuffer(GL_FRAMEBUFFER, id_);
  if (color(attachment).format() == TextureFormat::kR32UI) {
    const GLuint v[4] = {static_cast<GLuint>(value[0]), static_cast<GLuint>(value[1]),
                         static_cast<GLuint>(value[2]), static_cast<GLuint>(value[3])};
    glClearBufferuiv(GL_COLOR, attachment, v);
  } else {
    MS_CHECK(IsIntegerFormat(color(attachment).format())) << "ClearInt on a float attachment";
    glClearBufferiv(GL_COLOR, attachment, value.data());
  }
}

void Framebuffer::ClearDepth(float value) const {
  MS_CHECK(depth() != nullptr) << "ClearDepth on a framebuffer without depth";
  glBindFramebuffer(GL_FRAMEBUFFER, id_);
  glDepthMask(GL_TRUE);
  glClearBufferfv(GL_DEPTH, 0, &value);
}

namespace {

cv::Mat ReadPixels(uint32_t framebuffer, GLenum read_buffer, TextureFormat format, cv::Rect rect,
                   int width, int height) {
  if (rect.area() == 0) rect = cv::Rect(0, 0, width, height);
  MS_CHECK(rect.x >= 0 && rect.y >= 0 && rect.x + rect.width <= width &&
           rect.y + rect.height <= height)
      << "read-back rectangle " << rect << " outside " << width << "x" << height;
  const FormatInfo info = Info(format);
  cv::Mat out(rect.height, rect.width, info.cv_type);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
  if (read_buffer != GL_NONE) glReadBuffer(read_buffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glReadPixels(rect.x, rect.y, rect.width, rect.height, info.pixel_format, info.pixel_type,
               out.data);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  CheckGlError("framebuffer read-back");
  return out;
}

}  // namespace

cv::Mat Framebuffer::Read(int attachment, cv::Rect rect) const {
  const Texture2D& texture = color(attachment);
  return ReadPixels(id_, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(attachment), texture.format(),
                    rect, width_, height_);
}

cv::Mat Framebuffer::ReadDepth(cv::Rect rect) const {
  MS_CHECK(depth() != nullptr) << "ReadDepth on a framebuffer without depth";
  return ReadPixels(id_, GL_NONE, TextureFormat::kDepth32F, rect, width_, height_);
}

// `#define`s right after the #version line, then a #line that keeps the file's line numbers.
std::string InsertDefines(const std::string& text, const std::vector<std::string>& defines) {
  if (defines.empty()) return text;
  size_t pos = 0;
  int line = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    ++line;
    const std::string_view current(text.data() + pos, end - pos);
    if (current.find("#version") != std::string_view::npos) {
      std::string block;
      for (const std::string& d : defines) block += "#define " + d + "\n";
      block += "#line " + std::to_string(line + 1) + " 0\n";
      return text.substr(0, end + 1) + block + text.substr(std::min(end + 1, text.size()));
    }
    pos = end + 1;
  }
  throw InternalError("shader has no #version line; cannot insert #defines");
}

// ---------------------------------------------------------------------------------------------
// Layered framebuffers, double uniforms, array layers

void ShaderProgram::SetDouble(const std::string& uniform, double value) const {
  glProgramUniform1d(id(), Location(uniform), value);
}

Texture2D Texture2D::FromImage(const cv::Mat& image, TextureFormat format) {
  Texture2D texture(image.cols, image.rows, format);
  texture.Upload(image);
  return texture;
}

void Texture2DArray::BindImage(int unit, ImageAccess access) const {
  const GLenum mode = access == ImageAccess::kReadOnly    ? GL_READ_ONLY
                      : access == ImageAccess::kWriteOnly ? GL_WRITE_ONLY
                                                          : GL_READ_WRITE;
  glBindImageTexture(static_cast<GLuint>(unit), id_, 0, GL_TRUE, 0, mode,
                     Info(format_).internal_format);
}

cv::Mat Texture2DArray::DownloadLayer(int layer) const {
  MS_CHECK(layer >= 0 && layer < layers_) << "layer " << layer << " of " << layers_;
  const FormatInfo info = Info(format_);
  cv::Mat all(height_ * layers_, width_, info.cv_type);
  glBindTexture(GL_TEXTURE_2D_ARRAY, id_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTexImage(GL_TEXTURE_2D_ARRAY, 0, info.pixel_format, info.pixel_type, all.data);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  CheckGlError("texture array read-back");
  return all.rowRange(layer * height_, (layer + 1) * height_).clone();
}

LayeredFramebuffer::LayeredFramebuffer(const std::vector<const Texture2DArray*>& colors,
                                       const Texture2DArray& depth)
    : width_(depth.width()), height_(depth.height()), num_colors_(static_cast<int>(colors.size())) {
  glGenFramebuffers(1, &fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  std::vector<GLenum> buffers;
  for (size_t i = 0; i < colors.size(); ++i) {
    glFramebufferTexture(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i),
                         colors[i]->id(), 0);
    buffers.push_back(GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i));
  }
  glFramebufferTexture(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, depth.id(), 0);
  glDrawBuffers(static_cast<GLsizei>(buffers.size()), buffers.data());
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    glDeleteFramebuffers(1, &fbo_);
    throw InternalError(fmt::format("{}x{}x{} layered framebuffer incomplete (0x{:x})",
                                    depth.width(), depth.height(), depth.layers(), status));
  }
  CheckGlError("creating a layered framebuffer");
}

LayeredFramebuffer::~LayeredFramebuffer() {
  if (fbo_ != 0) glDeleteFramebuffers(1, &fbo_);
}

void LayeredFramebuffer::BindAndClear(const std::vector<Eigen::Vector4f>& colors, float depth,
                                      const cv::Rect& viewport) const {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
  glDepthMask(GL_TRUE);
  for (int i = 0; i < num_colors_; ++i) glClearBufferfv(GL_COLOR, i, colors[i].data());
  glClearBufferfv(GL_DEPTH, 0, &depth);
  glViewport(viewport.x, viewport.y, viewport.width, viewport.height);
}

}  // namespace ms::gl
