#include "tendril/render/impostor_baker.h"

#include "tendril/core/error.h"
#include "tendril/render/gl_util.h"
#include "tendril/render/offscreen.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <map>
#include <thread>

namespace tendril::render {
namespace {

const char* const kVertex = R"glsl(
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec2 aUv;
uniform mat4 uClipFromWorld;
out vec3 vNormal;
out vec2 vUv;
out vec3 vWorld;
void main() {
  vNormal = aNormal;
  vWorld = aPosition;
  vUv = aUv;
  gl_Position = uClipFromWorld * vec4(aPosition, 1.0);
}
)glsl";

// Base colour (linear factor times the sRGB texture, written sRGB-encoded) and the normal facing
// the viewer in the view's frame, its alpha marking leaves (1) and other surfaces (128 / 255);
// alpha-tested leaves are cut out at 0.5, and drawn only into the families they face.
const char* const kFragment = R"glsl(
in vec3 vNormal;
in vec2 vUv;
in vec3 vWorld;
uniform vec4 uBaseColor;
uniform bool uTextured;
uniform bool uAlphaMask;
uniform sampler2D uTexture;
uniform vec3 uRight, uUp, uFacing;
uniform float uLeafShare;
uniform bool uFamily;
layout(location = 0) out vec4 oColor;
layout(location = 1) out vec4 oNormal;
vec3 toLinear(vec3 c) { return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c)); }
vec3 toSrgb(vec3 c) { return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c)); }
void main() {
  vec4 c = uBaseColor;
  if (uTextured) {
    vec4 t = texture(uTexture, vec2(vUv.x, 1.0 - vUv.y));  // mesh v points up; row 0 is the image's top
    c.rgb *= toLinear(t.rgb);
    c.a *= t.a;
  }
  if (uAlphaMask && c.a < 0.5) discard;
  vec3 n = normalize(vNormal);
  // Leaves go to the families their blade faces (io/impostor.h): by the face's own normal.
  vec3 f = normalize(cross(dFdx(vWorld), dFdy(vWorld)));
  vec3 a = abs(f);
  if (uFamily && uAlphaMask && abs(dot(f, uFacing)) < uLeafShare * max(a.x, max(a.y, a.z))) discard;
  if (dot(n, uFacing) < 0.0) n = -n;  // double-sided: the side the viewer sees
  oColor = vec4(toSrgb(clamp(c.rgb, 0.0, 1.0)), 1.0);
  oNormal = vec4(vec3(dot(n, uRight), dot(n, uUp), dot(n, uFacing)) * 0.5 + 0.5, uAlphaMask ? 1.0 : 128.0 / 255.0);
}
)glsl";

// Clip coordinates of the view (column-major for glUniformMatrix4fv): x over the image's width,
// y from its bottom (−1) to its top (+1), z from the slab's +normal face (−1, nearest the
// camera) to its −normal face (+1).
std::array<float, 16> clipFromWorld(const io::ImpostorView& v) {
  const Eigen::Vector3d c = v.corner.cast<double>(), u = v.u.cast<double>(), dn = v.v.cast<double>();
  const Eigen::Vector3d n = v.normal.cast<double>().normalized();
  const Eigen::Vector3d right = u / u.squaredNorm();  // (p − c) · right ∈ [0, 1] across the width
  const Eigen::Vector3d down = dn / dn.squaredNorm();  // (p − c) · down ∈ [0, 1] down the height
  const double depth = double(v.hi) - double(v.lo);
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m.block<1, 3>(0, 0) = 2.0 * right.transpose();
  m(0, 3) = -2.0 * right.dot(c) - 1.0;
  m.block<1, 3>(1, 0) = -2.0 * down.transpose();
  m(1, 3) = 2.0 * down.dot(c) + 1.0;
  m.block<1, 3>(2, 0) = -2.0 / depth * n.transpose();
  m(2, 3) = 1.0 + 2.0 * (n.dot(c) + double(v.lo)) / depth;
  m(3, 3) = 1.0;
  std::array<float, 16> out;
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row) out[size_t(col * 4 + row)] = float(m(row, col));
  return out;
}

struct SurfaceBuffers {
  gl::VertexArray vao;
  gl::Buffer positions, normals, uvs, indices;
  GLsizei count = 0;
  GLuint texture = 0;
};

std::vector<io::ImpostorImages> bakeHere(const std::vector<io::ImpostorSurface>& surfaces,
                                         const std::vector<io::ImpostorView>& views) {
  OffscreenContext context;
  gl::Program program = gl::makeProgram("impostor bake", "", kVertex, kFragment);
  glUseProgram(program.get());
  const GLint uClip = glGetUniformLocation(program.get(), "uClipFromWorld");
  const GLint uBase = glGetUniformLocation(program.get(), "uBaseColor");
  const GLint uTextured = glGetUniformLocation(program.get(), "uTextured");
  const GLint uAlpha = glGetUniformLocation(program.get(), "uAlphaMask");
  const GLint uTexture = glGetUniformLocation(program.get(), "uTexture");
  const GLint uRight = glGetUniformLocation(program.get(), "uRight");
  const GLint uUp = glGetUniformLocation(program.get(), "uUp");
  const GLint uFacing = glGetUniformLocation(program.get(), "uFacing");
  const GLint uFamily = glGetUniformLocation(program.get(), "uFamily");
  glUniform1f(glGetUniformLocation(program.get(), "uLeafShare"), io::kImpostorLeafShare);
  glUniform1i(uTexture, 0);

  // Textures, each image once (clamp and repeat share it: the wrap mode is a sampler state,
  // set per draw).
  std::map<const io::Image*, gl::Texture> textures;
  for (const io::ImpostorSurface& s : surfaces) {
    if (!s.texture || s.texture->empty() || textures.count(s.texture)) continue;
    gl::Texture t = gl::makeTexture();
    glBindTexture(GL_TEXTURE_2D, t.get());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, s.texture->width, s.texture->height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 s.texture->rgba.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    textures.emplace(s.texture, std::move(t));
  }
  std::vector<SurfaceBuffers> buffers(surfaces.size());
  for (size_t i = 0; i < surfaces.size(); ++i) {
    const TriangleMesh& m = *surfaces[i].mesh;
    SurfaceBuffers& b = buffers[i];
    b.count = GLsizei(m.indices.size());
    if (b.count == 0) continue;
    b.vao = gl::makeVertexArray();
    glBindVertexArray(b.vao.get());
    auto attribute = [&](gl::Buffer& buffer, GLuint location, int components, const void* data, size_t bytes) {
      buffer = gl::makeBuffer();
      glBindBuffer(GL_ARRAY_BUFFER, buffer.get());
      glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(bytes), data, GL_STATIC_DRAW);
      glEnableVertexAttribArray(location);
      glVertexAttribPointer(location, components, GL_FLOAT, GL_FALSE, 0, nullptr);
    };
    attribute(b.positions, 0, 3, m.positions.data(), m.positions.size() * sizeof(Vec3));
    if (m.normals.size() == m.positions.size())
      attribute(b.normals, 1, 3, m.normals.data(), m.normals.size() * sizeof(Vec3));
    else
      glVertexAttrib3f(1, 0.0f, 0.0f, 1.0f);
    const bool textured = surfaces[i].texture && !surfaces[i].texture->empty() && m.uvs.size() == m.positions.size();
    if (textured) attribute(b.uvs, 2, 2, m.uvs.data(), m.uvs.size() * sizeof(Vec2));
    b.texture = textured ? textures.at(surfaces[i].texture).get() : 0;
    b.indices = gl::makeBuffer();
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b.indices.get());
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(m.indices.size() * sizeof(uint32_t)), nullptr, GL_STREAM_DRAW);
  }
  // Each view draws only the triangles that reach into its slab (the clip planes would discard
  // the rest anyway, so the images are the same; the order of those drawn is kept, so are ties
  // of depth): every slab pass would otherwise rasterise the whole plant, K times per family.
  std::vector<float> slabDepth;
  std::vector<uint32_t> kept;

  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  std::vector<io::ImpostorImages> out(views.size());
  for (size_t k = 0; k < views.size(); ++k) {
    const io::ImpostorView& v = views[k];
    gl::Framebuffer fbo = gl::makeFramebuffer();
    glBindFramebuffer(GL_FRAMEBUFFER, fbo.get());
    gl::Texture color = gl::makeTexture(), normal = gl::makeTexture();
    for (GLuint t : {color.get(), normal.get()}) {
      glBindTexture(GL_TEXTURE_2D, t);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, v.width, v.height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, color.get(), 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, normal.get(), 0);
    gl::Renderbuffer depth = gl::makeRenderbuffer();
    glBindRenderbuffer(GL_RENDERBUFFER, depth.get());
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, v.width, v.height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth.get());
    const GLenum drawBuffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, drawBuffers);
    gl::checkFramebuffer(GL_FRAMEBUFFER, "impostor bake");
    glViewport(0, 0, v.width, v.height);
    const float clearColor[4] = {0.0f, 0.0f, 0.0f, 0.0f}, clearNormal[4] = {0.5f, 0.5f, 1.0f, 0.0f};
    glClearBufferfv(GL_COLOR, 0, clearColor);
    glClearBufferfv(GL_COLOR, 1, clearNormal);
    glClear(GL_DEPTH_BUFFER_BIT);

    const std::array<float, 16> clip = clipFromWorld(v);
    glUniformMatrix4fv(uClip, 1, GL_FALSE, clip.data());
    const Vec3 right = v.u.normalized(), up = -v.v.normalized(), facing = v.normal.normalized();
    glUniform3f(uRight, right.x(), right.y(), right.z());
    glUniform3f(uUp, up.x(), up.y(), up.z());
    glUniform3f(uFacing, facing.x(), facing.y(), facing.z());
    glUniform1i(uFamily, v.surface < 0);
    glActiveTexture(GL_TEXTURE0);
    for (size_t i = 0; i < surfaces.size(); ++i) {
      const SurfaceBuffers& b = buffers[i];
      if (b.count == 0) continue;
      const io::ImpostorSurface& s = surfaces[i];
      // A family's slab shows the surfaces not on quads of their own; an own quad its surface.
      if (v.surface < 0 ? !io::inFamily(s, v.normal) : int(i) != v.surface) continue;
      glUniform4f(uBase, s.baseColor.x(), s.baseColor.y(), s.baseColor.z(), s.baseColor.w());
      glUniform1i(uTextured, b.texture != 0);
      glUniform1i(uAlpha, s.alphaMask);
      glBindTexture(GL_TEXTURE_2D, b.texture);
      if (b.texture) {
        const GLint wrap = s.repeat ? GL_REPEAT : GL_CLAMP_TO_EDGE;
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrap);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrap);
      }
      const TriangleMesh& m = *s.mesh;
      const float margin = 1e-3f * (v.hi - v.lo) + 1e-6f;
      const float lo = v.lo - margin, hi = v.hi + margin;
      slabDepth.resize(m.positions.size());
      for (size_t p = 0; p < m.positions.size(); ++p) slabDepth[p] = (m.positions[p] - v.corner).dot(v.normal);
      kept.clear();
      for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
        const float d0 = slabDepth[m.indices[t]], d1 = slabDepth[m.indices[t + 1]], d2 = slabDepth[m.indices[t + 2]];
        if (std::max({d0, d1, d2}) < lo || std::min({d0, d1, d2}) > hi) continue;
        kept.insert(kept.end(), m.indices.begin() + std::ptrdiff_t(t), m.indices.begin() + std::ptrdiff_t(t + 3));
      }
      if (kept.empty()) continue;
      glBindVertexArray(b.vao.get());
      glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(kept.size() * sizeof(uint32_t)), kept.data(), GL_STREAM_DRAW);
      glDrawElements(GL_TRIANGLES, GLsizei(kept.size()), GL_UNSIGNED_INT, nullptr);
    }
    // Read back, rows flipped to top-to-bottom.
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    for (int a = 0; a < 2; ++a) {
      io::Image& img = a == 0 ? out[k].color : out[k].normal;
      img.width = v.width;
      img.height = v.height;
      std::vector<uint8_t> raw(size_t(v.width) * size_t(v.height) * 4);
      glReadBuffer(a == 0 ? GL_COLOR_ATTACHMENT0 : GL_COLOR_ATTACHMENT1);
      glReadPixels(0, 0, v.width, v.height, GL_RGBA, GL_UNSIGNED_BYTE, raw.data());
      img.rgba.resize(raw.size());
      const size_t row = size_t(v.width) * 4;
      for (int y = 0; y < v.height; ++y)
        std::memcpy(img.rgba.data() + size_t(y) * row, raw.data() + size_t(v.height - 1 - y) * row, row);
    }
    const GLenum error = glGetError();
    if (error != GL_NO_ERROR)
      throw Error("OpenGL", "impostor", fmt::format("baking view {} failed: {}", k, gl::errorName(error)));
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  glBindVertexArray(0);
  buffers.clear();
  textures.clear();
  program.reset();
  return out;
}

}  // namespace

std::vector<io::ImpostorImages> RendererImpostorBaker::bake(const std::vector<io::ImpostorSurface>& surfaces,
                                                             const std::vector<io::ImpostorView>& views) {
  std::lock_guard lock(mutex_);
  std::vector<io::ImpostorImages> out;
  std::exception_ptr failed;
  std::thread worker([&] {
    try {
      out = bakeHere(surfaces, views);
    } catch (...) {
      failed = std::current_exception();
    }
  });
  worker.join();
  if (failed) std::rethrow_exception(failed);
  return out;
}

void installRendererImpostorBaker() { io::installImpostorBaker(std::make_shared<RendererImpostorBaker>()); }

}  // namespace tendril::render
