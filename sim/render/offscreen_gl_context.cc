#include "sim/render/offscreen_gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace graspbed::sim {
namespace {

// GL_VENDOR etc. without linking libGL/libOpenGL: the entry point comes from EGL, as for MuJoCo.
constexpr unsigned kGlVersion = 0x1F02;
constexpr unsigned kGlRenderer = 0x1F01;
using GetStringFn = const unsigned char* (*)(unsigned);

bool HasExtension(const char* extensions, const char* name) {
  if (extensions == nullptr) return false;
  const size_t length = std::strlen(name);
  for (const char* p = extensions; (p = std::strstr(p, name)) != nullptr; p += length) {
    const bool starts = p == extensions || p[-1] == ' ';
    const bool ends = p[length] == ' ' || p[length] == '\0';
    if (starts && ends) return true;
  }
  return false;
}

std::string EglErrorText(EGLint error) {
  char text[32];
  std::snprintf(text, sizeof(text), "EGL error 0x%04X", static_cast<unsigned>(error));
  return text;
}

struct Candidate {
  EGLDisplay display;
  const char* name;
};

// Displays worth trying, most headless first.
std::vector<Candidate> CandidateDisplays() {
  std::vector<Candidate> candidates;
  const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display != nullptr && HasExtension(client_extensions, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display != EGL_NO_DISPLAY) candidates.push_back({display, "surfaceless"});
  }
  auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  if (get_platform_display != nullptr && query_devices != nullptr &&
      HasExtension(client_extensions, "EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[8];
    EGLint count = 0;
    if (query_devices(8, devices, &count) == EGL_TRUE && count > 0) {
      EGLDisplay display = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[0], nullptr);
      if (display != EGL_NO_DISPLAY) candidates.push_back({display, "device"});
    }
  }
  EGLDisplay display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  if (display != EGL_NO_DISPLAY) candidates.push_back({display, "default display"});
  return candidates;
}

}  // namespace

OffscreenGlContext::OffscreenGlContext() {
  std::string tried;
  for (const Candidate& candidate : CandidateDisplays()) {
    EGLint major = 0;
    EGLint minor = 0;
    if (eglInitialize(candidate.display, &major, &minor) != EGL_TRUE) {
      tried += std::string(tried.empty() ? "" : "; ") + candidate.name +
               ": eglInitialize: " + EglErrorText(eglGetError());
      continue;
    }
    // 8-bit RGBA with depth and stencil; the surface type does not matter (MuJoCo draws into its own
    // framebuffer object), but some drivers only list configs that have one.
    const EGLint with_pbuffer[] = {EGL_RED_SIZE,
                                   8,
                                   EGL_GREEN_SIZE,
                                   8,
                                   EGL_BLUE_SIZE,
                                   8,
                                   EGL_ALPHA_SIZE,
                                   8,
                                   EGL_DEPTH_SIZE,
                                   24,
                                   EGL_STENCIL_SIZE,
                                   8,
                                   EGL_SURFACE_TYPE,
                                   EGL_PBUFFER_BIT,
                                   EGL_RENDERABLE_TYPE,
                                   EGL_OPENGL_BIT,
                                   EGL_NONE};
    const EGLint any_surface[] = {EGL_RED_SIZE,     8, EGL_GREEN_SIZE,      8,
                                  EGL_BLUE_SIZE,    8, EGL_DEPTH_SIZE,      24,
                                  EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                  EGL_NONE};
    EGLConfig config = nullptr;
    EGLint count = 0;
    if ((eglChooseConfig(candidate.display, with_pbuffer, &config, 1, &count) != EGL_TRUE || count < 1) &&
        (eglChooseConfig(candidate.display, any_surface, &config, 1, &count) != EGL_TRUE || count < 1)) {
      tried += std::string(tried.empty() ? "" : "; ") + candidate.name + ": no OpenGL config";
      continue;
    }
    // MuJoCo 2.2 draws with the fixed-function pipeline: desktop OpenGL, compatibility profile.
    if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
      tried += std::string(tried.empty() ? "" : "; ") + candidate.name + ": no desktop OpenGL API";
      continue;
    }
    EGLContext context = eglCreateContext(candidate.display, config, EGL_NO_CONTEXT, nullptr);
    if (context == EGL_NO_CONTEXT) {
      tried += std::string(tried.empty() ? "" : "; ") + candidate.name +
               ": eglCreateContext: " + EglErrorText(eglGetError());
      continue;
    }
    if (eglMakeCurrent(candidate.display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) != EGL_TRUE) {
      tried += std::string(tried.empty() ? "" : "; ") + candidate.name +
               ": eglMakeCurrent without a surface: " + EglErrorText(eglGetError());
      eglDestroyContext(candidate.display, context);
      continue;
    }
    display_ = candidate.display;
    context_ = context;
    const char* vendor = eglQueryString(candidate.display, EGL_VENDOR);
    description_ = "EGL " + std::to_string(major) + "." + std::to_string(minor) + " (" +
                   (vendor != nullptr ? vendor : "?") + ", " + candidate.name + ")";
    auto get_string = reinterpret_cast<GetStringFn>(eglGetProcAddress("glGetString"));
    if (get_string != nullptr) {
      const unsigned char* version = get_string(kGlVersion);
      const unsigned char* renderer = get_string(kGlRenderer);
      description_ += std::string(", OpenGL ") + (version ? reinterpret_cast<const char*>(version) : "?") +
                      " " + (renderer ? reinterpret_cast<const char*>(renderer) : "?");
    }
    return;
  }
  throw std::runtime_error(
      "offscreen rendering: no EGL display gives an OpenGL context (" +
      (tried.empty() ? std::string("no EGL display at all") : tried) +
      "); on Debian install libegl1 and libegl-mesa0 (Mesa's llvmpipe renders without a GPU)");
}

OffscreenGlContext::~OffscreenGlContext() {
  if (display_ == nullptr) return;
  // The display stays initialised: EGL hands every caller the same display per platform, and
  // eglTerminate would pull it from under other live contexts (another renderer in this process).
  if (eglGetCurrentContext() == context_)
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
}

void OffscreenGlContext::MakeCurrent() {
  if (eglGetCurrentContext() == context_) return;
  if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) != EGL_TRUE) {
    throw std::runtime_error("offscreen rendering: eglMakeCurrent: " + EglErrorText(eglGetError()));
  }
}

}  // namespace graspbed::sim
