#pragma once
/// An OpenGL context for rendering without a display, window system or GPU: EGL, on Mesa's
/// surfaceless platform first (software rasteriser llvmpipe when there is no GPU), then an EGL device,
/// then the default display. MuJoCo's mjr_* functions draw into the context that is current on the
/// calling thread, into their own offscreen framebuffer, so no EGL surface is needed.
///
/// Why EGL (Debian bookworm, libmujoco 2.2.2; docs/simulation.md, "Rendering stills"): libmujoco finds
/// the GL entry points through whichever of libGLX, libGL, libEGL or libOSMesa is loaded in the
/// process, so EGL needs nothing beyond libegl1 + libegl-mesa0 and no X server. OSMesa works as well
/// but is one more package and is gone from Mesa since 25.1; GLFW needs an X server (Xvfb).

#include <string>

namespace graspbed::sim {

/// An OpenGL context the renderer draws with: offscreen (OffscreenGlContext) or a window's (the viewer).
class GlContext {
 public:
  virtual ~GlContext() = default;
  /// Makes the context current on the calling thread. Throws std::runtime_error on failure.
  virtual void MakeCurrent() = 0;
};

/// Owns an EGL display and an OpenGL (desktop, compatibility) context. Not copyable, not movable.
/// Use it from one thread at a time.
class OffscreenGlContext : public GlContext {
 public:
  /// Creates the context and makes it current on this thread. Throws std::runtime_error saying what
  /// was tried and which package provides it when no EGL platform gives an OpenGL context.
  OffscreenGlContext();
  ~OffscreenGlContext() override;
  OffscreenGlContext(const OffscreenGlContext&) = delete;
  OffscreenGlContext& operator=(const OffscreenGlContext&) = delete;

  /// Makes the context current on the calling thread. Throws std::runtime_error on failure.
  void MakeCurrent() override;
  /// What was opened, e.g. "EGL 1.5 (Mesa Project, surfaceless), OpenGL 4.5 (compatibility) llvmpipe".
  const std::string& description() const { return description_; }

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  std::string description_;
};

}  // namespace graspbed::sim
