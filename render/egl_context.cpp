#include "render/egl_context.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>

#include <cstdlib>
#include <cstring>
#include <vector>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

constexpr const char* kInstallHint =
    "Off-screen rendering needs EGL and an OpenGL driver: on Debian install the packages libegl1 "
    "libegl-mesa0 libgl1-mesa-dri (Mesa's llvmpipe renders on the CPU, no GPU or display needed; "
    "building softbake also needs libegl-dev), or the NVIDIA driver's EGL on a GPU machine. "
    "--no-render skips the PNG frames.";

std::string eglErrorName(EGLint code) {
  switch (code) {
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
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
      return "EGL_BAD_SURFACE";
    default:
      return cat("EGL error 0x", std::hex, code);
  }
}

std::string lastEglError() {
  return eglErrorName(eglGetError());
}

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t length = std::strlen(name);
  for (const char* p = std::strstr(list, name); p; p = std::strstr(p + 1, name)) {
    const bool startOk = p == list || p[-1] == ' ';
    const bool endOk = p[length] == ' ' || p[length] == '\0';
    if (startOk && endOk) return true;
  }
  return false;
}

/// A display with an OpenGL core context current on it, or the reason there is none.
struct Attempt {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;
  std::string failure;
  bool initialised = false;  ///< a display came up, even if the context then failed
};

/// Initialises `display` and creates and binds an OpenGL ≥ 3.3 core context on it. On failure
/// everything made so far is released and `failure` says which step failed.
Attempt createContext(EGLDisplay display) {
  Attempt attempt;
  if (display == EGL_NO_DISPLAY) {
    attempt.failure = cat("no display (", lastEglError(), ")");
    return attempt;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    attempt.failure = cat("eglInitialize failed (", lastEglError(), ")");
    return attempt;
  }
  auto fail = [&](std::string reason) {
    if (attempt.context != EGL_NO_CONTEXT) {
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(display, attempt.context);
    }
    if (attempt.surface != EGL_NO_SURFACE) eglDestroySurface(display, attempt.surface);
    // Not eglTerminate: the display is shared by every context of the process on this platform.
    return Attempt{EGL_NO_DISPLAY, EGL_NO_CONTEXT, EGL_NO_SURFACE, std::move(reason), true};
  };
  if (!eglBindAPI(EGL_OPENGL_API))
    return fail(cat("EGL ", major, ".", minor, " has no desktop OpenGL (", lastEglError(), ")"));

  const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
  const bool surfaceless = hasExtension(extensions, "EGL_KHR_surfaceless_context");
  const EGLint configAttributes[] = {EGL_SURFACE_TYPE,
                                     EGL_PBUFFER_BIT,
                                     EGL_RENDERABLE_TYPE,
                                     EGL_OPENGL_BIT,
                                     EGL_RED_SIZE,
                                     8,
                                     EGL_GREEN_SIZE,
                                     8,
                                     EGL_BLUE_SIZE,
                                     8,
                                     EGL_NONE};
  EGLConfig config = EGL_NO_CONFIG_KHR;
  EGLint configCount = 0;
  if (!eglChooseConfig(display, configAttributes, &config, 1, &configCount) || configCount < 1) {
    // Rendering goes to framebuffer objects, so a context without a config will do.
    if (!surfaceless || !hasExtension(extensions, "EGL_KHR_no_config_context"))
      return fail(cat("no OpenGL-renderable EGL config (", lastEglError(), ")"));
    config = EGL_NO_CONFIG_KHR;
  }
  const EGLint contextAttributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                      3,
                                      EGL_CONTEXT_MINOR_VERSION,
                                      3,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
  attempt.context = eglCreateContext(display, config, EGL_NO_CONTEXT, contextAttributes);
  if (attempt.context == EGL_NO_CONTEXT)
    return fail(cat("no OpenGL 3.3 core context (", lastEglError(), ")"));
  if (!surfaceless) {
    const EGLint pbufferAttributes[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    attempt.surface = eglCreatePbufferSurface(display, config, pbufferAttributes);
    if (attempt.surface == EGL_NO_SURFACE)
      return fail(cat("no pbuffer surface (", lastEglError(), ")"));
  }
  if (!eglMakeCurrent(display, attempt.surface, attempt.surface, attempt.context))
    return fail(cat("eglMakeCurrent failed (", lastEglError(), ")"));
  attempt.display = display;
  attempt.initialised = true;
  return attempt;
}

PFNEGLGETPLATFORMDISPLAYEXTPROC platformDisplayFunction() {
  return reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
}

Attempt trySurfaceless() {
  const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto getPlatformDisplay = platformDisplayFunction();
  if (!hasExtension(clientExtensions, "EGL_MESA_platform_surfaceless") || !getPlatformDisplay)
    return {EGL_NO_DISPLAY, EGL_NO_CONTEXT, EGL_NO_SURFACE,
            "EGL_MESA_platform_surfaceless is not available (no Mesa EGL vendor)"};
  return createContext(getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, nullptr, nullptr));
}

Attempt tryDevices(std::string& name) {
  const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto getPlatformDisplay = platformDisplayFunction();
  auto queryDevices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  if (!hasExtension(clientExtensions, "EGL_EXT_platform_device") || !getPlatformDisplay ||
      !queryDevices)
    return {EGL_NO_DISPLAY, EGL_NO_CONTEXT, EGL_NO_SURFACE,
            "EGL_EXT_platform_device is not available"};
  std::vector<EGLDeviceEXT> devices(16);
  EGLint count = 0;
  if (!queryDevices(EGLint(devices.size()), devices.data(), &count) || count < 1)
    return {EGL_NO_DISPLAY, EGL_NO_CONTEXT, EGL_NO_SURFACE,
            cat("eglQueryDevicesEXT found no device (", lastEglError(), ")")};
  std::string failures;
  bool initialised = false;
  for (EGLint i = 0; i < count; ++i) {
    Attempt attempt =
        createContext(getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr));
    if (attempt.display != EGL_NO_DISPLAY) {
      name = cat("device ", i);
      return attempt;
    }
    failures += cat(i ? "; " : "", "device ", i, ": ", attempt.failure);
    initialised = initialised || attempt.initialised;
  }
  return {EGL_NO_DISPLAY, EGL_NO_CONTEXT, EGL_NO_SURFACE, failures, initialised};
}

Attempt tryRawPlatform(const std::string& text) {
  char* end = nullptr;
  const unsigned long value = std::strtoul(text.c_str(), &end, 16);
  if (!end || *end != '\0' || text.size() < 3)
    throw Error(cat("unknown EGL platform '", text,
                    "': use auto, surfaceless, device, default or a hexadecimal EGL enum"));
  auto getPlatformDisplay = platformDisplayFunction();
  if (!getPlatformDisplay)
    return {EGL_NO_DISPLAY, EGL_NO_CONTEXT, EGL_NO_SURFACE,
            "eglGetPlatformDisplayEXT is not available"};
  return createContext(getPlatformDisplay(EGLenum(value), nullptr, nullptr));
}

}  // namespace

std::string requestedEglPlatform(const EglOptions& options) {
  if (!options.platform.empty()) return options.platform;
  const char* variable = std::getenv("SOFTBAKE_EGL_PLATFORM");
  return variable && *variable ? std::string(variable) : std::string("auto");
}

EglContext::EglContext(const EglOptions& options) {
  const std::string requested = requestedEglPlatform(options);
  std::string failures;
  bool anyDisplay = false;
  auto consider = [&](const std::string& name, Attempt attempt) {
    anyDisplay = anyDisplay || attempt.initialised;
    if (display_ || attempt.display == EGL_NO_DISPLAY) {
      if (!display_) failures += cat(failures.empty() ? "" : "; ", name, ": ", attempt.failure);
      return;
    }
    display_ = attempt.display;
    context_ = attempt.context;
    surface_ = attempt.surface;
    platform_ = name;
  };
  const bool automatic = requested == "auto";
  if (automatic || requested == "surfaceless") consider("surfaceless", trySurfaceless());
  if (!display_ && (automatic || requested == "device")) {
    std::string name = "device";
    Attempt attempt = tryDevices(name);
    consider(name, std::move(attempt));
  }
  if (!display_ && (automatic || requested == "default"))
    consider("default", createContext(eglGetDisplay(EGL_DEFAULT_DISPLAY)));
  if (!automatic && requested != "surfaceless" && requested != "device" && requested != "default")
    consider(cat("platform ", requested), tryRawPlatform(requested));
  if (!display_) {
    const std::string message = cat("cannot create an off-screen OpenGL 3.3 context through EGL (",
                                    failures, "). ", kInstallHint);
    if (!anyDisplay) throw EglDisplayUnavailable(message);
    throw Error(message);
  }
}

EglContext::~EglContext() {
  if (eglGetCurrentContext() == context_)
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  // A context still current on another thread is destroyed when that thread releases it.
  eglDestroyContext(display_, context_);
  if (surface_) eglDestroySurface(display_, surface_);
}

void EglContext::makeCurrent() {
  if (eglGetCurrentContext() == context_ && eglGetCurrentSurface(EGL_DRAW) == surface_) return;
  if (!eglMakeCurrent(display_, surface_, surface_, context_))
    throw Error(cat("eglMakeCurrent failed (", lastEglError(), ")"));
}

std::string EglContext::describe() const {
  const auto text = [](GLenum name) {
    const GLubyte* value = glGetString(name);
    return value ? std::string(reinterpret_cast<const char*>(value)) : std::string("?");
  };
  return cat(text(GL_RENDERER), ", OpenGL ", text(GL_VERSION));
}

}  // namespace softbake
