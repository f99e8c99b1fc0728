// Small OpenGL helpers for the renderer: owning handles and shader programs with readable
// errors. Every function needs a current OpenGL 4.1+ core context (function pointers come from
// libepoxy, so the same code runs in a GLFW window and in an EGL offscreen context).
#pragma once

#include <epoxy/gl.h>

#include <string>
#include <utility>

namespace tendril::render::gl {

// A GL object name with its delete function; move-only.
template <void (*Delete)(GLuint)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(GLuint name) : name_(name) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : name_(std::exchange(o.name_, 0)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      name_ = std::exchange(o.name_, 0);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  GLuint get() const { return name_; }
  explicit operator bool() const { return name_ != 0; }
  void reset() {
    if (name_) Delete(name_);
    name_ = 0;
  }

 private:
  GLuint name_ = 0;
};

void deleteBuffer(GLuint name);
void deleteVertexArray(GLuint name);
void deleteTexture(GLuint name);
void deleteFramebuffer(GLuint name);
void deleteRenderbuffer(GLuint name);
void deleteProgram(GLuint name);

using Buffer = Handle<deleteBuffer>;
using VertexArray = Handle<deleteVertexArray>;
using Texture = Handle<deleteTexture>;
using Framebuffer = Handle<deleteFramebuffer>;
using Renderbuffer = Handle<deleteRenderbuffer>;
using Program = Handle<deleteProgram>;

Buffer makeBuffer();
VertexArray makeVertexArray();
Texture makeTexture();
Framebuffer makeFramebuffer();
Renderbuffer makeRenderbuffer();

// Compiles and links "#version 410 core" + defines + each source. A compile or link error is a
// programming error: it throws std::logic_error with the shader log and the failing lines.
Program makeProgram(const std::string& name, const std::string& defines, const std::string& vertex,
                    const std::string& fragment);

// Orphans the buffer's storage (growing `capacity` by half again when `bytes` exceeds it) and
// uploads with glBufferSubData. `target`'s binding is left pointing at the buffer.
void uploadStream(GLenum target, const Buffer& buffer, const void* data, size_t bytes, size_t& capacity);

// Throws std::runtime_error naming `what` when an incomplete framebuffer is bound to `target`.
void checkFramebuffer(GLenum target, const char* what);

// "GL_INVALID_OPERATION" etc. for a glGetError value.
const char* errorName(GLenum error);

}  // namespace tendril::render::gl
