// Non-copyable, movable RAII wrappers of OpenGL objects, for every GL user in the project (depth
// rendering, synthetic images, the sweep kernel). No GL headers here: ids are uint32_t (GLuint)
// and formats are our own enums. Raw GL calls on these objects go through gl/gl_api.h in .cc
// files (id() gives the name).
//
// Rules:
// - A GlContext (gl/context.h) must be current on this thread when an object is created, used
//   or destroyed; destroy objects before their context.
// - Editing an object binds it to a scratch target (GL 4.3 has no direct state access): buffers
//   to GL_COPY_WRITE_BUFFER, textures to the active unit. Nothing restores previous bindings.
// - Image layout: texture/framebuffer row 0 is the first row of the cv::Mat given or returned
//   (no flips). gl/projection.h renders image row r into framebuffer row r, so read-backs come
//   out in image order and texture coordinate v = y / height addresses image row y.
// - Failures (compile/link logs, incomplete framebuffers, GL errors) throw InternalError.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <unordered_map>
#include <vector>

namespace ms::gl {

// ---------------------------------------------------------------------------------------------
// Shader programs

enum class ShaderStage { kVertex, kGeometry, kFragment, kCompute };
std::string ShaderStageName(ShaderStage stage);
// From a file name's extension: .vert .geom .frag .comp; throws InternalError otherwise.
ShaderStage ShaderStageFromName(const std::string& file_name);

struct ShaderSource {
  ShaderStage stage = ShaderStage::kVertex;
  std::string name;  // for messages ("mesh_depth.frag")
  std::string text;  // GLSL, starting with #version
  // Names of GLSL source strings 1, 2, ... (files #included; see shaders::Expand) so that
  // compiler messages "1:12" can be shown as "noise.glsl:12".
  std::vector<std::string> included_names;
};

class ShaderProgram {
 public:
  // Compiles every stage and links. Either vertex (+ optional geometry) + fragment stages, or
  // one compute stage. Throws InternalError "<program>: <name> (<stage>) failed to compile:"
  // followed by the driver's log, each message followed by the offending source line.
  ShaderProgram(std::string name, const std::vector<ShaderSource>& sources);
  // Embedded shaders (shaders/) by file name, #includes expanded; each of `defines` ("NAME" or
  // "NAME VALUE") becomes a `#define` right after the #version line of every stage.
  static ShaderProgram FromEmbedded(const std::vector<std::string>& names,
                                    const std::vector<std::string>& defines = {});

  ~ShaderProgram();
  ShaderProgram(ShaderProgram&& other) noexcept;
  ShaderProgram& operator=(ShaderProgram&& other) noexcept;
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  uint32_t id() const { return id_; }
  const std::string& name() const { return name_; }
  void Use() const;

  // Uniform location, cached; -1 when the program has no such active uniform (the compiler
  // drops unused ones), in which case the setters below do nothing. Setters work without Use().
  int Location(const std::string& uniform) const;
  bool HasUniform(const std::string& uniform) const { return Location(uniform) >= 0; }
  void Set(const std::string& uniform, int value) const;
  void Set(const std::string& uniform, uint32_t value) const;
  void Set(const std::string& uniform, float value) const;
  void Set(const std::string& uniform, const Eigen::Vector2f& value) const;
  void Set(const std::string& uniform, const Eigen::Vector3f& value) const;
  void Set(const std::string& uniform, const Eigen::Vector4f& value) const;
  void Set(const std::string& uniform, const Eigen::Vector2i& value) const;
  void Set(const std::string& uniform, const Eigen::Matrix3f& value) const;  // column-major
  void Set(const std::string& uniform, const Eigen::Matrix4f& value) const;
  void Set(const std::string& uniform, const std::vector<float>& values) const;  // float[]
  // A `double` uniform (GL 4.0). Not an overload of Set: a double literal there means float.
  void SetDouble(const std::string& uniform, double value) const;

  // Compute programs: Use() + glDispatchCompute(groups). Follow with MemoryBarrier() before
  // reading what the shader wrote through another path (buffer download, texture fetch).
  void Dispatch(int groups_x, int groups_y = 1, int groups_z = 1) const;
  // The local size declared by the compute shader.
  Eigen::Vector3i WorkGroupSize() const;

 private:
  ShaderProgram() = default;
  void Release();
  uint32_t id_ = 0;
  std::string name_;
  mutable std::unordered_map<std::string, int> locations_;
};

// glMemoryBarrier(GL_ALL_BARRIER_BITS): writes of earlier shader invocations (SSBO, image stores)
// become visible to later commands.
void MemoryBarrier();
// glFinish: wait for the GPU (timing).
void Finish();

// How many work groups (or batches) of `per` items cover `count` items: ceil(count / per).
inline int DivideRoundingUp(int64_t count, int64_t per) {
  return static_cast<int>((count + per - 1) / per);
}

// ---------------------------------------------------------------------------------------------
// Buffers

enum class BufferUsage {
  kStaticDraw,
  kDynamicDraw,
  kStreamDraw,
  kStaticRead,
  kDynamicRead,
  kDynamicCopy
};

class Buffer {
 public:
  Buffer();  // a name with no storage yet
  explicit Buffer(size_t bytes, const void* data = nullptr,
                  BufferUsage usage = BufferUsage::kStaticDraw);
  template <typename T>
  static Buffer FromVector(const std::vector<T>& values,
                           BufferUsage usage = BufferUsage::kStaticDraw) {
    return Buffer(values.size() * sizeof(T), values.data(), usage);
  }
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  // (Re)allocates storage (contents undefined unless data is given).
  void Allocate(size_t bytes, const void* data = nullptr,
                BufferUsage usage = BufferUsage::kStaticDraw);
  void Upload(size_t offset, size_t bytes, const void* data);
  void Download(size_t offset, size_t bytes, void* out) const;
  template <typename T>
  std::vector<T> DownloadVector(size_t count, size_t first = 0) const {
    std::vector<T> out(count);
    Download(first * sizeof(T), count * sizeof(T), out.data());
    return out;
  }
  // Fills the whole buffer with a repeated 32-bit value (e.g. zeroing counters).
  void Fill(uint32_t value);

  // Indexed binding points, matching `layout(binding = N)` in GLSL.
  void BindStorage(int binding) const;        // shader storage block (std430)
  void BindUniformBlock(int binding) const;   // uniform block (std140)
  void BindAtomicCounter(int binding) const;  // atomic_uint

  size_t size() const { return size_; }
  uint32_t id() const { return id_; }

 private:
  void Release();
  uint32_t id_ = 0;
  size_t size_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Vertex arrays

class VertexArray {
 public:
  VertexArray();
  ~VertexArray();
  VertexArray(VertexArray&& other) noexcept;
  VertexArray& operator=(VertexArray&& other) noexcept;
  VertexArray(const VertexArray&) = delete;
  VertexArray& operator=(const VertexArray&) = delete;

  // Attribute `location` reads `components` floats per vertex from `buffer` (byte stride and
  // offset; stride 0 = tightly packed). SetIntAttribute: int32 components (GLSL ivecN).
  void SetFloatAttribute(int location, const Buffer& buffer, int components, size_t stride = 0,
                         size_t offset = 0);
  void SetIntAttribute(int location, const Buffer& buffer, int components, size_t stride = 0,
                       size_t offset = 0);
  // uint32 indices for DrawIndexed.
  void SetIndexBuffer(const Buffer& buffer);

  void Bind() const;
  // Draw calls with the current program. Triangles from `count` indices / vertices.
  void DrawIndexedTriangles(size_t index_count, size_t first_index = 0) const;
  void DrawTriangles(size_t vertex_count, size_t first_vertex = 0) const;
  void DrawPoints(size_t vertex_count, size_t first_vertex = 0) const;

  uint32_t id() const { return id_; }

 private:
  void Release();
  uint32_t id_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Textures

// Formats and the cv::Mat type they exchange: kR8 CV_8U, kRGBA8 CV_8UC4, kR32F CV_32F, kRG32F
// CV_32FC2, kRGBA32F CV_32FC4, kR32I CV_32S, kR32UI CV_32S (same bits), kDepth32F CV_32F.
enum class TextureFormat { kR8, kRGBA8, kR32F, kRG32F, kRGBA32F, kR32I, kR32UI, kDepth32F };
int CvTypeOf(TextureFormat format);
std::string TextureFormatName(TextureFormat format);
bool IsIntegerFormat(TextureFormat format);

enum class TextureFilter { kNearest, kLinear, kLinearMipmap };     // kLinearMipmap = trilinear
enum class TextureWrap { kClampToEdge, kRepeat, kClampToBorder };  // border = transparent black
enum class ImageAccess { kReadOnly, kWriteOnly, kReadWrite };

class Texture2D {
 public:
  // Immutable storage (glTexStorage2D) with `levels` mip levels. Filter: nearest; wrap: clamp.
  Texture2D(int width, int height, TextureFormat format, int levels = 1);
  // A texture of `format` holding `image` (CvTypeOf(format), level 0 only).
  static Texture2D FromImage(const cv::Mat& image, TextureFormat format);
  ~Texture2D();
  Texture2D(Texture2D&& other) noexcept;
  Texture2D& operator=(Texture2D&& other) noexcept;
  Texture2D(const Texture2D&) = delete;
  Texture2D& operator=(const Texture2D&) = delete;

  // `image` must have CvTypeOf(format()) and fit at (x, y) of `level`. Row 0 = texture row 0.
  void Upload(const cv::Mat& image, int level = 0);
  void UploadRect(int x, int y, const cv::Mat& image, int level = 0);
  cv::Mat Download(int level = 0) const;
  void GenerateMipmaps();
  void SetFilter(TextureFilter filter);
  void SetWrap(TextureWrap wrap);
  void Bind(int unit) const;  // for a sampler uniform set to `unit`
  // For image load/store (`layout(binding = unit, r32f) uniform image2D`).
  void BindImage(int unit, ImageAccess access, int level = 0) const;

  int width() const { return width_; }
  int height() const { return height_; }
  int levels() const { return levels_; }
  TextureFormat format() const { return format_; }
  uint32_t id() const { return id_; }

 private:
  void Release();
  uint32_t id_ = 0;
  int width_ = 0, height_ = 0, levels_ = 1;
  TextureFormat format_ = TextureFormat::kRGBA8;
};

// A stack of equally sized layers (GLSL sampler2DArray), e.g. several photographs.
class Texture2DArray {
 public:
  Texture2DArray(int width, int height, int layers, TextureFormat format, int levels = 1);
  ~Texture2DArray();
  Texture2DArray(Texture2DArray&& other) noexcept;
  Texture2DArray& operator=(Texture2DArray&& other) noexcept;
  Texture2DArray(const Texture2DArray&) = delete;
  Texture2DArray& operator=(const Texture2DArray&) = delete;

  void UploadLayer(int layer, const cv::Mat& image, int level = 0);
  void GenerateMipmaps();
  void SetFilter(TextureFilter filter);
  void SetWrap(TextureWrap wrap);
  void Bind(int unit) const;
  // Every layer, level 0, as an image unit (GLSL image2DArray) of the array's format.
  void BindImage(int unit, ImageAccess access) const;
  // One layer of level 0. Reads the whole array: for captures and tests, not hot paths.
  cv::Mat DownloadLayer(int layer) const;

  int width() const { return width_; }
  int height() const { return height_; }
  int layers() const { return layers_; }
  TextureFormat format() const { return format_; }
  uint32_t id() const { return id_; }

 private:
  void Release();
  uint32_t id_ = 0;
  int width_ = 0, height_ = 0, layers_ = 0, levels_ = 1;
  TextureFormat format_ = TextureFormat::kRGBA8;
};

// ---------------------------------------------------------------------------------------------
// Framebuffers

// An offscreen render target owning its textures: colour attachment i (fragment output
// `layout(location = i)`) of color_formats[i], plus an optional kDepth32F depth texture.
class Framebuffer {
 public:
  Framebuffer(int width, int height, const std::vector<TextureFormat>& color_formats,
              bool with_depth = true);
  ~Framebuffer();
  Framebuffer(Framebuffer&& other) noexcept;
  Framebuffer& operator=(Framebuffer&& other) noexcept;
  Framebuffer(const Framebuffer&) = delete;
  Framebuffer& operator=(const Framebuffer&) = delete;

  // Binds for drawing and reading, sets the viewport to the whole target and enables every
  // colour attachment as a draw buffer.
  void Bind() const;
  static void BindDefault();  // framebuffer 0 (none exists on a surfaceless context)

  // Clears one attachment: float/normalised formats take `value`, integer ones `int_value`.
  void Clear(int attachment, const Eigen::Vector4f& value) const;
  void ClearInt(int attachment, const Eigen::Vector4i& int_value) const;
  void ClearDepth(float value) const;

  // Reads attachment `attachment` (or the depth texture) into a cv::Mat of CvTypeOf(format),
  // row 0 = framebuffer row 0. `rect` picks a sub-rectangle (empty: all); it must lie inside.
  cv::Mat Read(int attachment, cv::Rect rect = cv::Rect()) const;
  cv::Mat ReadDepth(cv::Rect rect = cv::Rect()) const;

  int width() const { return width_; }
  int height() const { return height_; }
  int num_colors() const { return static_cast<int>(colors_.size()); }
  const Texture2D& color(int attachment) const;
  const Texture2D* depth() const { return depth_.empty() ? nullptr : &depth_.front(); }
  uint32_t id() const { return id_; }

 private:
  void Release();
  uint32_t id_ = 0;
  int width_ = 0, height_ = 0;
  std::vector<Texture2D> colors_;
  std::vector<Texture2D> depth_;  // zero or one
};

// Colour texture arrays and a depth texture array it does not own, attached as one layered
// framebuffer: an instanced draw routes each instance to its layer (gl_Layer), colour output i
// to colors[i]. All arrays have the depth array's size.
class LayeredFramebuffer {
 public:
  LayeredFramebuffer(const std::vector<const Texture2DArray*>& colors, const Texture2DArray& depth);
  ~LayeredFramebuffer();
  LayeredFramebuffer(const LayeredFramebuffer&) = delete;
  LayeredFramebuffer& operator=(const LayeredFramebuffer&) = delete;

  // Binds for drawing, clears colour i to colors[i] (all layers) and depth, and sets the
  // viewport to `viewport` (x, y, width, height).
  void BindAndClear(const std::vector<Eigen::Vector4f>& colors, float depth,
                    const cv::Rect& viewport) const;

 private:
  int width_, height_, num_colors_;
  uint32_t fbo_ = 0;
};

// Inserts `#define NAME` / `#define NAME VALUE` lines right after a shader's #version line,
// followed by a #line so compiler messages keep the file's line numbers. Throws InternalError
// if there is no #version line.
std::string InsertDefines(const std::string& text, const std::vector<std::string>& defines);

}  // namespace ms::gl
