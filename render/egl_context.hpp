#pragma once
/// A headless OpenGL context through EGL: no window system, no display server.
///
/// Platforms are tried in order until one gives an OpenGL ≥ 3.3 core context:
///   1. EGL_PLATFORM_SURFACELESS_MESA: Mesa's display with no window system (llvmpipe on a machine
///      without a GPU, the GPU's Mesa driver otherwise);
///   2. EGL_EXT_platform_device: each EGL device in turn (how NVIDIA's driver renders headless);
///   3. eglGetDisplay(EGL_DEFAULT_DISPLAY).
/// A failure says what each platform answered and which Debian packages provide EGL and Mesa.

#include <string>

#include "core/error.hpp"

namespace softbake {

/// What EglContext throws when no EGL platform gives a display that initialises: the machine has
/// no EGL driver at all (a container without libegl-mesa0, say), so nothing can render here. Any
/// later failure, such as a display without OpenGL 3.3, is a plain softbake::Error: there is a
/// driver, and it failed. Tests skip on the first and fail on the second.
class EglDisplayUnavailable : public Error {
 public:
  using Error::Error;
};

struct EglOptions {
  /// "auto" (the order above), "surfaceless", "device", "default", or a raw EGL platform enum in
  /// hexadecimal ("0x31DD") passed to eglGetPlatformDisplayEXT as is: an invalid one is how tests
  /// exercise the failure path. Empty: the SOFTBAKE_EGL_PLATFORM environment variable, else "auto".
  std::string platform;
};

/// The platform EglOptions asks for, after the environment variable: "auto" when neither is set.
std::string requestedEglPlatform(const EglOptions& options);

/// Owns an EGL display connection and an OpenGL core context, current on the thread that
/// constructed it. GL calls must come from that thread only. Not copyable or movable: the context
/// is bound to this object's thread for its whole life.
class EglContext {
 public:
  /// Creates the context and makes it current. Throws softbake::Error naming what is missing and
  /// the packages to install, EglDisplayUnavailable when not even a display came up; never hangs.
  explicit EglContext(const EglOptions& options = {});
  /// Releases the context from this thread (when current here) and destroys it.
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  /// Makes the context current on the calling thread (after another thread released it).
  void makeCurrent();
  /// "surfaceless", "device 0", "default": the platform that worked.
  const std::string& platform() const { return platform_; }
  /// GL_RENDERER and GL_VERSION, for logs: "llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core ...)".
  std::string describe() const;

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  void* surface_ = nullptr;  // EGLSurface: a 1×1 pbuffer, only without EGL_KHR_surfaceless_context
  std::string platform_;
};

}  // namespace softbake
