#include "tendril/render/gl_util.h"

#include <fmt/format.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace tendril::render::gl {

void deleteBuffer(GLuint name) { glDeleteBuffers(1, &name); }
void deleteVertexArray(GLuint name) { glDeleteVertexArrays(1, &name); }
void deleteTexture(GLuint name) { glDeleteTextures(1, &name); }
void deleteFramebuffer(GLuint name) { glDeleteFramebuffers(1, &name); }
void deleteRenderbuffer(GLuint name) { glDeleteRenderbuffers(1, &name); }
void deleteProgram(GLuint name) { glDeleteProgram(name); }

Buffer makeBuffer() {
  GLuint n = 0;
  glGenBuffers(1, &n);
  return Buffer(n);
}
VertexArray makeVertexArray() {
  GLuint n = 0;
  glGenVertexArrays(1, &n);
  return VertexArray(n);
}
Texture makeTexture() {
  GLuint n = 0;
  glGenTextures(1, &n);
  return Texture(n);
}
Framebuffer makeFramebuffer() {
  GLuint n = 0;
  glGenFramebuffers(1, &n);
  return Framebuffer(n);
}
Renderbuffer makeRenderbuffer() {
  GLuint n = 0;
  glGenRenderbuffers(1, &n);
  return Renderbuffer(n);
}

namespace {

// The source with line numbers, so a compiler message "0:57(12)" can be matched by eye.
std::string numbered(const std::string& source) {
  std::istringstream in(source);
  std::string line, out;
  for (int n = 1; std::getline(in, line); ++n) out += fmt::format("{:4} {}\n", n, line);
  return out;
}

GLuint compile(const std::string& name, GLenum stage, const std::string& source) {
  GLuint shader = glCreateShader(stage);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(size_t(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw std::logic_error(fmt::format("{} {} shader does not compile:\n{}\n{}", name,
                                       stage == GL_VERTEX_SHADER ? "vertex" : "fragment", log.data(),
                                       numbered(source)));
  }
  return shader;
}

}  // namespace

Program makeProgram(const std::string& name, const std::string& defines, const std::string& vertex,
                    const std::string& fragment) {
  const std::string header = "#version 410 core\n" + defines;
  GLuint vs = compile(name, GL_VERTEX_SHADER, header + vertex);
  GLuint fs = 0;
  try {
    fs = compile(name, GL_FRAGMENT_SHADER, header + fragment);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  Program program(glCreateProgram());
  glAttachShader(program.get(), vs);
  glAttachShader(program.get(), fs);
  glLinkProgram(program.get());
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(program.get(), GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetProgramiv(program.get(), GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(size_t(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program.get(), length, nullptr, log.data());
    throw std::logic_error(fmt::format("{} program does not link:\n{}", name, log.data()));
  }
  return program;
}

void uploadStream(GLenum target, const Buffer& buffer, const void* data, size_t bytes, size_t& capacity) {
  glBindBuffer(target, buffer.get());
  if (bytes > capacity) capacity = std::max<size_t>(bytes + bytes / 2, 4096);
  // Fresh storage every frame (orphaning), so this upload never waits for the GPU to finish
  // reading the previous frame's data.
  glBufferData(target, GLsizeiptr(capacity), nullptr, GL_STREAM_DRAW);
  if (bytes > 0) glBufferSubData(target, 0, GLsizeiptr(bytes), data);
}

void checkFramebuffer(GLenum target, const char* what) {
  GLenum status = glCheckFramebufferStatus(target);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error(fmt::format("{} framebuffer is incomplete (status 0x{:x})", what, status));
}

const char* errorName(GLenum error) {
  switch (error) {
    case GL_NO_ERROR: return "GL_NO_ERROR";
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    default: return "unknown GL error";
  }
}

}  // namespace tendril::render::gl
