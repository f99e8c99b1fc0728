// The studio's window: a GLFW window with an OpenGL 4.1+ core context (libepoxy loads the entry
// points the renderer uses), Dear ImGui on top of it, an offscreen colour + depth target the
// 3D viewport is drawn into, and read-back of the whole window for headless screenshots.
#pragma once

#include "tendril/io/image.h"

#include <string>

struct GLFWwindow;

namespace tendril::studio {

class Window {
 public:
  // Throws Error("display", "", ...) when GLFW cannot open a window with an OpenGL 4.1 core
  // context (no X display: run under xvfb-run).
  Window(int width, int height, const std::string& title);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  GLFWwindow* handle() const { return window_; }
  bool shouldClose() const;
  void requestClose();
  // Framebuffer size in pixels (differs from the window size on high-DPI screens).
  int framebufferWidth() const;
  int framebufferHeight() const;
  float contentScale() const;  // framebuffer pixels per window unit

  // Polls events and starts an ImGui frame.
  void beginFrame();
  // Draws ImGui over whatever the frame holds; does not swap.
  void renderUi();
  void swap();
  // The back buffer as an image, top row first (call after renderUi, before swap).
  io::Image readBackBuffer() const;
  // "OpenGL 4.5 (Core Profile) Mesa ..., llvmpipe ..." of the window's context.
  std::string glDescription() const;

 private:
  GLFWwindow* window_ = nullptr;
};

// A framebuffer the 3D view is drawn into at the viewport's size, then copied into the
// window's back buffer at the viewport's place.
class ViewportTarget {
 public:
  ViewportTarget() = default;
  ~ViewportTarget();
  ViewportTarget(const ViewportTarget&) = delete;
  ViewportTarget& operator=(const ViewportTarget&) = delete;

  // (Re)allocates when the size changed, binds it for drawing and sets the viewport.
  void bind(int width, int height);
  // Copies the target into the default framebuffer with its top-left corner at window pixel
  // (x, y) (y measured from the top), and binds the default framebuffer again.
  void blitToWindow(int x, int y, int windowHeight) const;

 private:
  void release();
  unsigned fbo_ = 0, color_ = 0, depth_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace tendril::studio
