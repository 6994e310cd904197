// Headless OpenGL 4.3+ core contexts through EGL, without a window system.
//
// Backends, in the order kAuto tries them:
//   1. an EGL device that is real hardware (EGL_EXT_device_enumeration + EGL_EXT_platform_device;
//      NVIDIA's driver on a GPU machine),
//   2. Mesa's surfaceless platform (EGL_MESA_platform_surfaceless; llvmpipe on a CPU machine),
//   3. any remaining EGL device (Mesa lists its software rasteriser as a device too).
// The context is made current on the constructing thread; GL calls (and the gl/ wrappers, which
// must be destroyed before their context) belong to that thread. Several contexts may coexist;
// MakeCurrent() switches between them.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "base/options.h"

namespace ms::gl {

enum class GlBackend { kAuto, kDevice, kSurfaceless };

// "auto", "device", "surfaceless"; throws InputError naming `field` otherwise.
GlBackend ParseGlBackend(const std::string& name, const std::string& field = "--gl-backend");
std::string GlBackendName(GlBackend backend);
// The names of GlBackend's values, for option groups (base/options.h).
const std::vector<std::pair<const char*, GlBackend>>& OptionChoices(GlBackend);

// --gl-backend, declared once for every command that takes it.
struct GlBackendOption {
  static constexpr const char* kOptionGroup = "";
#define MS_OPTION_LIST "gl/gl_backend_option_def.h"
#include "base/option_group_members.h"
  void Check() const { CheckOptionGroup(*this); }  // throws InputError naming the flag
};

struct GlContextOptions {
  GlBackend backend = GlBackend::kAuto;  // see the list above
  int device_index = -1;  // with kDevice: the EGL device to use (-1: the first that works)
  int min_major = 4;      // the oldest core profile accepted; 4.3 has compute shaders and SSBOs
  int min_minor = 3;
  bool debug_output = false;     // a debug context whose KHR_debug messages go to the log (slow)
  bool use_clip_control = true;  // reversed-Z depth where available; false: GL's default
                                 // [-1, 1] depth as on drivers without it (tests that path)
  void Check() const;
};

struct GlInfo {
  std::string platform;  // "EGL device 0 (/dev/dri/renderD128)", "Mesa surfaceless", ...
  std::string vendor;    // GL_VENDOR
  std::string renderer;  // GL_RENDERER
  std::string version;   // GL_VERSION
  std::string glsl_version;
  int major = 0, minor = 0;
  bool software = false;      // a CPU rasteriser (llvmpipe, softpipe, swrast)
  bool clip_control = false;  // glClipControl (GL 4.5 or ARB_clip_control): reversed-Z depth
  int max_texture_size = 0;
  // "llvmpipe (LLVM 15.0.6, 256 bits) | 4.5 (Core Profile) Mesa 22.3.6 | Mesa surfaceless"
  std::string Summary() const;
};

class GlContext {
 public:
  // Throws InternalError naming every backend tried and why it failed.
  explicit GlContext(const GlContextOptions& options = {});
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  const GlInfo& info() const;
  void MakeCurrent() const;
  bool IsCurrent() const;
  // Unbinds the context from the calling thread (if bound), so another thread may bind it: an
  // EGL context is current on at most one thread at a time.
  void ReleaseCurrent() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What GlContext(options) gets, as GlInfo::Summary(), or "unavailable: <why>". Creates and
// destroys a context; for `manisweep info`.
std::string DescribeGl(const GlContextOptions& options = {});

}  // namespace ms::gl
