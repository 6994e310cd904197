#include "gl/context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include "base/error.h"
#include "base/log.h"
#include "gl/gl_api.h"

namespace ms::gl {
namespace {

bool HasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t length = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += length) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[length] == ' ' || p[length] == '\0';
    if (starts && ends) return true;
  }
  return false;
}

std::string EglErrorName(EGLint error) {
  switch (error) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE:
      return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP:
      return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW:
      return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
      return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST:
      return "EGL_CONTEXT_LOST";
    default:
      return "EGL error 0x" + fmt::format("{:x}", error);
  }
}

// eglTerminate is not reference counted, and eglGetPlatformDisplay returns the same handle for
// the same arguments, so two GlContexts on one display must not terminate it under each other.
std::mutex display_mutex;
std::map<EGLDisplay, int> display_users;

void AcquireDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(display_mutex);
  ++display_users[display];
}

void ReleaseDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(display_mutex);
  auto it = display_users.find(display);
  if (it == display_users.end()) return;
  if (--it->second == 0) {
    display_users.erase(it);
    eglTerminate(display);
  }
}

struct EglEntryPoints {
  PFNEGLQUERYDEVICESEXTPROC query_devices = nullptr;
  PFNEGLQUERYDEVICESTRINGEXTPROC query_device_string = nullptr;
  PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display = nullptr;
  std::string client_extensions;
};

EglEntryPoints LoadEntryPoints() {
  EglEntryPoints e;
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  e.client_extensions = client ? client : "";
  e.query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  e.query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglGetProcAddress("eglQueryDeviceStringEXT"));
  e.get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  return e;
}

void APIENTRY DebugCallback(GLenum, GLenum type, GLuint, GLenum severity, GLsizei,
                            const GLchar* message, const void*) {
  if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) {
    spdlog::trace("GL: {}", message);
  } else if (type == GL_DEBUG_TYPE_ERROR || severity == GL_DEBUG_SEVERITY_HIGH) {
    spdlog::warn("GL: {}", message);
  } else {
    spdlog::debug("GL: {}", message);
  }
}

const char* GlString(GLenum name) {
  const GLubyte* s = glGetString(name);
  return s ? reinterpret_cast<const char*>(s) : "";
}

}  // namespace

std::string GlErrorName(GLenum error) {
  switch (error) {
    case GL_NO_ERROR:
      return "GL_NO_ERROR";
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW:
      return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW:
      return "GL_STACK_OVERFLOW";
    default:
      return fmt::format("GL error 0x{:x}", error);
  }
}

void CheckGlError(const char* what) {
  std::string errors;
  for (int i = 0; i < 16; ++i) {  // a lost context may return errors forever
    const GLenum error = glGetError();
    if (error == GL_NO_ERROR) break;
    errors += (errors.empty() ? "" : ", ") + GlErrorName(error);
  }
  if (!errors.empty()) throw InternalError(std::string(what) + ": " + errors);
}

GlBackend ParseGlBackend(const std::string& name, const std::string& field) {
  if (name == "auto") return GlBackend::kAuto;
  if (name == "device") return GlBackend::kDevice;
  if (name == "surfaceless") return GlBackend::kSurfaceless;
  throw InputError(field + ": unknown OpenGL backend '" + name +
                   "' (use auto, device or surfaceless)");
}

const std::vector<std::pair<const char*, GlBackend>>& OptionChoices(GlBackend) {
  static const std::vector<std::pair<const char*, GlBackend>> choices = {
      {"auto", GlBackend::kAuto},
      {"device", GlBackend::kDevice},
      {"surfaceless", GlBackend::kSurfaceless}};
  return choices;
}

std::string GlBackendName(GlBackend backend) {
  switch (backend) {
    case GlBackend::kAuto:
      return "auto";
    case GlBackend::kDevice:
      return "device";
    case GlBackend::kSurfaceless:
      return "surfaceless";
  }
  return "unknown";
}

void GlContextOptions::Check() const {
  if (device_index < -1) throw InputError("gl.device_index: must be -1 (auto) or >= 0");
  if (min_major < 4 || (min_major == 4 && min_minor < 3)) {
    throw InputError("gl.min_major/min_minor: manisweep needs at least OpenGL 4.3");
  }
  if (min_minor < 0 || min_minor > 9) throw InputError("gl.min_minor: must be in [0, 9]");
}

std::string GlInfo::Summary() const { return renderer + " | " + version + " | " + platform; }

struct GlContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;  // a 1x1 pbuffer where surfaceless contexts are missing
  GlInfo info;

  // Tries one display; on failure returns false with `why` set and leaves nothing behind.
  bool TryDisplay(EGLDisplay candidate, const std::string& platform, const GlContextOptions& o,
                  std::string* why) {
    if (candidate == EGL_NO_DISPLAY) {
      *why = "no display (" + EglErrorName(eglGetError()) + ")";
      return false;
    }
    EGLint egl_major = 0, egl_minor = 0;
    if (!eglInitialize(candidate, &egl_major, &egl_minor)) {
      *why = "eglInitialize failed (" + EglErrorName(eglGetError()) + ")";
      return false;
    }
    AcquireDisplay(candidate);
    display = candidate;
    if (TryContext(platform, o, why)) return true;
    Release();
    return false;
  }

  bool TryContext(const std::string& platform, const GlContextOptions& o, std::string* why) {
    if (!eglBindAPI(EGL_OPENGL_API)) {
      *why = "desktop OpenGL not offered (eglBindAPI: " + EglErrorName(eglGetError()) + ")";
      return false;
    }
    const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
    const bool surfaceless = HasExtension(extensions, "EGL_KHR_surfaceless_context");
    const bool no_config = HasExtension(extensions, "EGL_KHR_no_config_context");
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!surfaceless || !no_config) {
      const EGLint attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                   EGL_OPENGL_BIT, EGL_NONE};
      EGLint count = 0;
      if (!eglChooseConfig(display, attributes, &config, 1, &count) || count < 1) {
        *why = "no OpenGL pbuffer config (" + EglErrorName(eglGetError()) + ")";
        return false;
      }
    }
    // Newest first: some drivers refuse versions above what they support, others round up.
    std::string refused;
    for (int minor = 6; minor >= 0 && context == EGL_NO_CONTEXT; --minor) {
      if (4 == o.min_major && minor < o.min_minor) break;
      const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                   4,
                                   EGL_CONTEXT_MINOR_VERSION,
                                   minor,
                                   EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                   EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                   EGL_CONTEXT_OPENGL_DEBUG,
                                   o.debug_output ? EGL_TRUE : EGL_FALSE,
                                   EGL_NONE};
      context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes);
      if (context == EGL_NO_CONTEXT) refused = EglErrorName(eglGetError());
    }
    if (context == EGL_NO_CONTEXT) {
      *why = fmt::format("no OpenGL {}.{}+ core context ({})", o.min_major, o.min_minor, refused);
      return false;
    }
    if (!surfaceless) {
      const EGLint attributes[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      surface = eglCreatePbufferSurface(display, config, attributes);
      if (surface == EGL_NO_SURFACE) {
        *why = "no surfaceless contexts and no pbuffer (" + EglErrorName(eglGetError()) + ")";
        return false;
      }
    }
    if (!eglMakeCurrent(display, surface, surface, context)) {
      *why = "eglMakeCurrent failed (" + EglErrorName(eglGetError()) + ")";
      return false;
    }
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    info.platform = platform;
    info.vendor = GlString(GL_VENDOR);
    info.renderer = GlString(GL_RENDERER);
    info.version = GlString(GL_VERSION);
    info.glsl_version = GlString(GL_SHADING_LANGUAGE_VERSION);
    info.major = major;
    info.minor = minor;
    if (major < o.min_major || (major == o.min_major && minor < o.min_minor)) {
      *why = fmt::format("{} offers OpenGL {}.{} only", info.renderer, major, minor);
      return false;
    }
    for (const char* soft : {"llvmpipe", "softpipe", "swrast", "SwiftShader"}) {
      if (info.renderer.find(soft) != std::string::npos) info.software = true;
    }
    info.clip_control = major > 4 || (major == 4 && minor >= 5);
    GLint count = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &count);
    for (GLint i = 0; i < count && !info.clip_control; ++i) {
      const GLubyte* name = glGetStringi(GL_EXTENSIONS, i);
      if (name && std::strcmp(reinterpret_cast<const char*>(name), "GL_ARB_clip_control") == 0) {
        info.clip_control = true;
      }
    }
    if (!o.use_clip_control) info.clip_control = false;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &info.max_texture_size);
    if (o.debug_output) {
      glEnable(GL_DEBUG_OUTPUT);
      glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
      glDebugMessageCallback(DebugCallback, nullptr);
    }
    glGetError();  // start from a clean error state
    return true;
  }

  void Release() {
    if (display == EGL_NO_DISPLAY) return;
    if (eglGetCurrentContext() == context && context != EGL_NO_CONTEXT) {
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
    if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
    surface = EGL_NO_SURFACE;
    context = EGL_NO_CONTEXT;
    ReleaseDisplay(display);
    display = EGL_NO_DISPLAY;
  }
};

GlContext::GlContext(const GlContextOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Check();
  const EglEntryPoints egl = LoadEntryPoints();
  std::vector<std::string> failures;
  const bool want_devices = options.backend != GlBackend::kSurfaceless;
  const bool want_surfaceless = options.backend != GlBackend::kDevice;

  // Devices: hardware ones first; software ones are kept for after surfaceless.
  struct Device {
    EGLDeviceEXT handle;
    int index;
    std::string label;
  };
  std::vector<Device> hardware, software;
  const bool device_platform =
      HasExtension(egl.client_extensions.c_str(), "EGL_EXT_platform_device") && egl.query_devices &&
      egl.get_platform_display;
  if (want_devices && !device_platform) {
    failures.push_back("EGL devices: EGL_EXT_device_enumeration/EGL_EXT_platform_device missing");
  } else if (want_devices) {
    EGLint count = 0;
    std::vector<EGLDeviceEXT> devices(16);
    if (!egl.query_devices(static_cast<EGLint>(devices.size()), devices.data(), &count)) {
      failures.push_back("EGL devices: eglQueryDevicesEXT failed (" + EglErrorName(eglGetError()) +
                         ")");
      count = 0;
    }
    if (count == 0 && failures.empty()) failures.push_back("EGL devices: none found");
    for (int i = 0; i < count; ++i) {
      if (options.device_index >= 0 && i != options.device_index) continue;
      const char* device_extensions =
          egl.query_device_string ? egl.query_device_string(devices[i], EGL_EXTENSIONS) : nullptr;
      std::string label = "EGL device " + std::to_string(i);
      if (HasExtension(device_extensions, "EGL_EXT_device_drm") && egl.query_device_string) {
        if (const char* file = egl.query_device_string(devices[i], EGL_DRM_DEVICE_FILE_EXT)) {
          label += std::string(" (") + file + ")";
        }
      }
      const bool is_software = HasExtension(device_extensions, "EGL_MESA_device_software");
      if (is_software) label += " (Mesa software)";
      (is_software ? software : hardware).push_back({devices[i], i, label});
    }
    if (options.device_index >= 0 && options.device_index >= count) {
      failures.push_back(
          fmt::format("EGL device {}: only {} device(s)", options.device_index, count));
    }
  }
  auto try_device = [&](const Device& device) {
    std::string why;
    const EGLDisplay display =
        egl.get_platform_display(EGL_PLATFORM_DEVICE_EXT, device.handle, nullptr);
    if (impl_->TryDisplay(display, device.label, options, &why)) return true;
    failures.push_back(device.label + ": " + why);
    return false;
  };
  for (const Device& device : hardware) {
    if (try_device(device)) break;
  }
  if (impl_->display == EGL_NO_DISPLAY && want_surfaceless) {
    if (!HasExtension(egl.client_extensions.c_str(), "EGL_MESA_platform_surfaceless") ||
        !egl.get_platform_display) {
      failures.push_back("Mesa surfaceless: EGL_MESA_platform_surfaceless missing");
    } else {
      std::string why;
      const EGLDisplay display =
          egl.get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (!impl_->TryDisplay(display, "Mesa surfaceless", options, &why)) {
        failures.push_back("Mesa surfaceless: " + why);
      }
    }
  }
  for (const Device& device : software) {
    if (impl_->display != EGL_NO_DISPLAY) break;
    try_device(device);
  }
  if (impl_->display == EGL_NO_DISPLAY) {
    std::string message = "no usable OpenGL " + std::to_string(options.min_major) + "." +
                          std::to_string(options.min_minor) +
                          "+ core context through EGL (backend " + GlBackendName(options.backend) +
                          "):";
    for (const std::string& f : failures) message += " [" + f + "]";
    message +=
        ". A GPU needs its vendor's EGL driver (NVIDIA: libnvidia-egl); without one, install "
        "Debian's libegl-mesa0 and libgl1-mesa-dri for llvmpipe.";
    throw InternalError(message);
  }
  spdlog::debug("OpenGL: {}", impl_->info.Summary());
}

GlContext::~GlContext() { impl_->Release(); }

const GlInfo& GlContext::info() const { return impl_->info; }

void GlContext::MakeCurrent() const {
  if (!eglMakeCurrent(impl_->display, impl_->surface, impl_->surface, impl_->context)) {
    throw InternalError("eglMakeCurrent failed (" + EglErrorName(eglGetError()) + ")");
  }
}

bool GlContext::IsCurrent() const { return eglGetCurrentContext() == impl_->context; }

void GlContext::ReleaseCurrent() const {
  if (IsCurrent()) eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

std::string DescribeGl(const GlContextOptions& options) {
  try {
    GlContext context(options);
    return context.info().Summary();
  } catch (const std::exception& e) {
    return std::string("unavailable: ") + e.what();
  }
}

}  // namespace ms::gl
