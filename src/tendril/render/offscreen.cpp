#include "tendril/render/offscreen.h"

#include "tendril/core/error.h"
#include "tendril/core/timer.h"
#include "tendril/render/gl_util.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <set>
#include <mutex>
#include <string_view>
#include <vector>

namespace tendril::render {
namespace {

const char* eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

// A display, once initialised, stays so for the life of the process: eglTerminate would end it
// for every context in the process (several OffscreenContexts — tests, a preview beside a
// render — may share one), and it unloads the driver, whose few lasting allocations then look
// leaked to LeakSanitizer (sanitizer builds) and must be made again by the next context.
std::mutex gDisplayMutex;
std::set<EGLDisplay> gInitialised;

bool initialiseDisplay(EGLDisplay display) {
  std::lock_guard lock(gDisplayMutex);
  if (gInitialised.count(display)) return true;
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) return false;
  gInitialised.insert(display);
  return true;
}

constexpr int kContextVersions[][2] = {{4, 6}, {4, 5}, {4, 3}, {4, 1}};

}  // namespace

struct OffscreenContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;
  std::string description;

  // Makes a current 4.1+ core context on `display`; on failure returns why and leaves nothing.
  std::string tryDisplay(EGLDisplay dpy, bool pbuffer) {
    if (dpy == EGL_NO_DISPLAY) return fmt::format("no display ({})", eglErrorName(eglGetError()));
    if (!initialiseDisplay(dpy)) return fmt::format("eglInitialize failed ({})", eglErrorName(eglGetError()));
    auto fail = [&](std::string why) {
      if (context != EGL_NO_CONTEXT) eglDestroyContext(dpy, context);
      if (surface != EGL_NO_SURFACE) eglDestroySurface(dpy, surface);
      context = EGL_NO_CONTEXT;
      surface = EGL_NO_SURFACE;
      return why;
    };
    if (!eglBindAPI(EGL_OPENGL_API)) return fail(fmt::format("no desktop OpenGL API ({})", eglErrorName(eglGetError())));
    const char* extensions = eglQueryString(dpy, EGL_EXTENSIONS);
    if (!pbuffer && !hasExtension(extensions, "EGL_KHR_surfaceless_context"))
      return fail("EGL_KHR_surfaceless_context is not supported");
    // No surface type requirement for surfaceless contexts (the default would be a window).
    const EGLint configAttribs[] = {EGL_SURFACE_TYPE, pbuffer ? EGL_PBUFFER_BIT : 0,
                                    EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                    EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8,
                                    EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configs = 0;
    if (!eglChooseConfig(dpy, configAttribs, &config, 1, &configs) || configs == 0)
      return fail(fmt::format("no RGB8 OpenGL config{}", pbuffer ? " with pbuffers" : ""));
    std::string tried;
    for (const auto& v : kContextVersions) {
      const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, v[0], EGL_CONTEXT_MINOR_VERSION, v[1],
                                EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
      context = eglCreateContext(dpy, config, EGL_NO_CONTEXT, attribs);
      if (context != EGL_NO_CONTEXT) break;
      tried += fmt::format("{}{}.{} ({})", tried.empty() ? "" : ", ", v[0], v[1], eglErrorName(eglGetError()));
    }
    if (context == EGL_NO_CONTEXT) return fail("no core context of version " + tried);
    if (pbuffer) {
      const EGLint surfaceAttribs[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
      surface = eglCreatePbufferSurface(dpy, config, surfaceAttribs);
      if (surface == EGL_NO_SURFACE) return fail(fmt::format("no pbuffer ({})", eglErrorName(eglGetError())));
    }
    if (!eglMakeCurrent(dpy, surface, surface, context))
      return fail(fmt::format("eglMakeCurrent failed ({})", eglErrorName(eglGetError())));
    if (epoxy_gl_version() < 41) {
      const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
      eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      return fail(fmt::format("the context is only OpenGL {}", version ? version : "?"));
    }
    display = dpy;
    return {};
  }
};

OffscreenContext::OffscreenContext() : impl_(std::make_unique<Impl>()) {
  std::string failures;  // "what was tried: why it failed; ..."
  auto note = [&](std::string_view what) {
    if (!failures.empty()) failures += "; ";
    failures += what;
  };
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  std::string method;
  auto attempt = [&](const std::string& name, EGLDisplay dpy, bool pbuffer) {
    std::string why = impl_->tryDisplay(dpy, pbuffer);
    if (why.empty()) {
      method = name;
      return true;
    }
    note(name + ": " + why);
    return false;
  };

  bool ok = false;
  if (hasExtension(client, "EGL_MESA_platform_surfaceless"))
    ok = attempt("EGL surfaceless (Mesa)",
                 eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr), false);
  else
    note("EGL surfaceless: EGL_MESA_platform_surfaceless is not supported");

  if (!ok) {
    auto queryDevices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    if (hasExtension(client, "EGL_EXT_platform_device") && queryDevices) {
      EGLDeviceEXT devices[16];
      EGLint count = 0;
      if (queryDevices(16, devices, &count) && count > 0) {
        for (EGLint i = 0; i < count && !ok; ++i)
          ok = attempt(fmt::format("EGL device {}", i),
                       eglGetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr), false);
      } else {
        note("EGL devices: none found");
      }
    } else {
      note("EGL devices: EGL_EXT_platform_device is not supported");
    }
  }
  if (!ok) ok = attempt("EGL default display with a pbuffer", eglGetDisplay(EGL_DEFAULT_DISPLAY), true);
  if (!ok) throw Error("OpenGL", "", "cannot create an OpenGL 4.1+ core context for offscreen rendering. Tried " + failures);
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  impl_->description = fmt::format("{}, OpenGL {}.{} core, {}", method, major, minor, renderer ? renderer : "?");
}

OffscreenContext::~OffscreenContext() {
  Impl& m = *impl_;
  if (eglGetCurrentContext() == m.context) eglMakeCurrent(m.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(m.display, m.context);
  if (m.surface != EGL_NO_SURFACE) eglDestroySurface(m.display, m.surface);
}

void OffscreenContext::makeCurrent() const {
  if (!eglMakeCurrent(impl_->display, impl_->surface, impl_->surface, impl_->context))
    throw Error("OpenGL", "", fmt::format("eglMakeCurrent failed ({})", eglErrorName(eglGetError())));
}

const std::string& OffscreenContext::description() const { return impl_->description; }

namespace {

// Mesa's CPU rasterisers, where multisampling is far slower than supersampling.
bool softwareRasterizer() {
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  std::string renderer = r ? r : "";
  return renderer.find("llvmpipe") != std::string::npos || renderer.find("softpipe") != std::string::npos;
}

// Averages each k × k block of `big` (rows bottom-up, as read) in linear light into `out`
// (rows top-down).
void downsample(const std::vector<uint8_t>& big, int k, io::Image& out) {
  static const std::array<float, 256> toLinear = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      float c = float(i) / 255.0f;
      t[size_t(i)] = c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
    }
    return t;
  }();
  constexpr int kEncodeSteps = 4096;
  static const std::array<uint8_t, kEncodeSteps + 1> toSrgb = [] {
    std::array<uint8_t, kEncodeSteps + 1> t{};
    for (int i = 0; i <= kEncodeSteps; ++i) {
      float c = float(i) / float(kEncodeSteps);
      float e = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
      t[size_t(i)] = uint8_t(std::lround(std::clamp(e, 0.0f, 1.0f) * 255.0f));
    }
    return t;
  }();
  const size_t bigStride = size_t(out.width) * size_t(k) * 4;
  const float inv = 1.0f / float(k * k);
  for (int y = 0; y < out.height; ++y) {
    const size_t bigRow0 = size_t(out.height - 1 - y) * size_t(k);
    for (int x = 0; x < out.width; ++x) {
      float sum[4] = {0.0f, 0.0f, 0.0f, 0.0f};
      for (int dy = 0; dy < k; ++dy) {
        const uint8_t* p = &big[(bigRow0 + size_t(dy)) * bigStride + size_t(x) * size_t(k) * 4];
        for (int dx = 0; dx < k; ++dx, p += 4) {
          for (int c = 0; c < 3; ++c) sum[c] += toLinear[p[c]];
          sum[3] += float(p[3]);
        }
      }
      uint8_t* o = out.pixel(x, y);
      for (int c = 0; c < 3; ++c) o[c] = toSrgb[size_t(std::lround(sum[c] * inv * float(kEncodeSteps)))];
      o[3] = uint8_t(std::lround(sum[3] * inv));
    }
  }
}

}  // namespace

struct OffscreenTarget::Impl {
  int width = 0, height = 0;
  int scale = 1;    // supersampling factor per axis
  int msaa = 1;     // multisamples
  gl::Framebuffer msaaFbo, resolveFbo;
  gl::Renderbuffer msaaColor, msaaDepth, color, depth;
};

OffscreenTarget::OffscreenTarget(int width, int height, int samples) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  GLint maxSize = 0, maxSamples = 1, maxViewport[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &maxSize);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, maxViewport);
  glGetIntegerv(GL_MAX_SAMPLES, &maxSamples);
  const int limit = std::min<int>(maxSize, std::min(maxViewport[0], maxViewport[1]));
  if (width > limit || height > limit)
    throw Error("render settings", width > limit ? "width" : "height",
                fmt::format("{}×{} exceeds this OpenGL's largest framebuffer ({} pixels a side)", width, height,
                            limit));
  m.width = width;
  m.height = height;
  if (samples > 1 && softwareRasterizer()) {
    m.scale = std::min(4, int(std::ceil(std::sqrt(double(samples)) - 1e-9)));
    while (m.scale > 1 && std::max(width, height) * m.scale > limit) --m.scale;
  } else {
    m.msaa = std::clamp(samples, 1, std::max(1, int(maxSamples)));
  }
  const int fw = width * m.scale, fh = height * m.scale;

  auto storage = [&](gl::Renderbuffer& rb, GLenum format, int s) {
    rb = gl::makeRenderbuffer();
    glBindRenderbuffer(GL_RENDERBUFFER, rb.get());
    if (s > 1)
      glRenderbufferStorageMultisample(GL_RENDERBUFFER, s, format, fw, fh);
    else
      glRenderbufferStorage(GL_RENDERBUFFER, format, fw, fh);
  };
  storage(m.color, GL_RGBA8, 1);
  storage(m.depth, GL_DEPTH_COMPONENT24, 1);
  m.resolveFbo = gl::makeFramebuffer();
  glBindFramebuffer(GL_FRAMEBUFFER, m.resolveFbo.get());
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m.color.get());
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m.depth.get());
  gl::checkFramebuffer(GL_FRAMEBUFFER, "offscreen");
  if (m.msaa > 1) {
    storage(m.msaaColor, GL_RGBA8, m.msaa);
    storage(m.msaaDepth, GL_DEPTH_COMPONENT24, m.msaa);
    m.msaaFbo = gl::makeFramebuffer();
    glBindFramebuffer(GL_FRAMEBUFFER, m.msaaFbo.get());
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m.msaaColor.get());
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m.msaaDepth.get());
    gl::checkFramebuffer(GL_FRAMEBUFFER, "offscreen multisample");
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

OffscreenTarget::~OffscreenTarget() = default;

int OffscreenTarget::width() const { return impl_->width; }
int OffscreenTarget::height() const { return impl_->height; }
int OffscreenTarget::framebufferWidth() const { return impl_->width * impl_->scale; }
int OffscreenTarget::framebufferHeight() const { return impl_->height * impl_->scale; }
int OffscreenTarget::samples() const { return impl_->scale * impl_->scale * impl_->msaa; }
bool OffscreenTarget::supersampled() const { return impl_->scale > 1; }

void OffscreenTarget::bind() const {
  const Impl& m = *impl_;
  glBindFramebuffer(GL_FRAMEBUFFER, m.msaa > 1 ? m.msaaFbo.get() : m.resolveFbo.get());
  glViewport(0, 0, framebufferWidth(), framebufferHeight());
}

io::Image OffscreenTarget::read() const {
  const Impl& m = *impl_;
  const int fw = framebufferWidth(), fh = framebufferHeight();
  if (m.msaa > 1) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, m.msaaFbo.get());
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, m.resolveFbo.get());
    glBlitFramebuffer(0, 0, fw, fh, 0, 0, fw, fh, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.resolveFbo.get());
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  std::vector<uint8_t> rows(size_t(fw) * size_t(fh) * 4);
  glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  GLenum error = glGetError();
  if (error != GL_NO_ERROR)
    throw std::runtime_error(fmt::format("reading the offscreen image failed: {}", gl::errorName(error)));
  io::Image image;
  image.width = m.width;
  image.height = m.height;
  image.rgba.resize(size_t(m.width) * size_t(m.height) * 4);
  if (m.scale > 1) {
    downsample(rows, m.scale, image);
  } else {
    // OpenGL's first row is the bottom one; images start at the top.
    const size_t stride = size_t(m.width) * 4;
    for (int y = 0; y < m.height; ++y)
      std::memcpy(&image.rgba[size_t(y) * stride], &rows[size_t(m.height - 1 - y) * stride], stride);
  }
  return image;
}

OffscreenRenderer::OffscreenRenderer()
    : context_(std::make_unique<OffscreenContext>()), renderer_(std::make_unique<Renderer>()) {}

OffscreenRenderer::~OffscreenRenderer() {
  // GL objects can only be deleted with their context current; if it cannot be made current
  // any more, they go away with the context itself.
  try {
    context_->makeCurrent();
  } catch (const Error&) {
  }
  target_.reset();
  renderer_.reset();
}

io::Image OffscreenRenderer::render(const RenderScene& scene, const Camera& camera, const RenderSettings& settings) {
  validateRenderSettings(settings, "render settings");
  Timer timer;
  context_->makeCurrent();
  if (!target_ || target_->width() != settings.width || target_->height() != settings.height ||
      targetSamples_ != settings.samples) {
    target_.reset();
    target_ = std::make_unique<OffscreenTarget>(settings.width, settings.height, settings.samples);
    targetSamples_ = settings.samples;
  }
  target_->bind();
  RenderSettings scaled = settings;  // line widths are in image pixels
  scaled.lineWidth *= float(target_->framebufferWidth()) / float(settings.width);
  renderer_->render(scene, camera, scaled, target_->framebufferWidth(), target_->framebufferHeight());
  io::Image image = target_->read();
  lastRenderMs_ = timer.milliseconds();
  return image;
}

}  // namespace tendril::render
