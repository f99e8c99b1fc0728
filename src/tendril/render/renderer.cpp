#include "tendril/render/renderer.h"

#include "tendril/core/error.h"
#include "tendril/core/hash.h"
#include "tendril/core/timer.h"
#include "tendril/env/primitives.h"
#include "tendril/mesh/leaf_mesh.h"
#include "tendril/render/gl_util.h"
#include "tendril/render/plant_instances.h"
#include "tendril/render/shaders.h"
#include "tendril/render/texture_layers.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace tendril::render {
namespace {

// Air speed on a scale of 0–1: blue (still), green (mid-scale), red (1 and faster).
Vec3 airColor(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  const Vec3 blue(0.05f, 0.2f, 0.9f), green(0.1f, 0.75f, 0.15f), red(0.9f, 0.08f, 0.04f);
  return t < 0.5f ? Vec3((1.0f - 2.0f * t) * blue + 2.0f * t * green) : Vec3((2.0f - 2.0f * t) * green + (2.0f * t - 1.0f) * red);
}

constexpr int kMaxLights = 8;         // matches kMaxLights in shaders::kLighting
constexpr int kLeafRows = 4;          // quads along a blade: enough for the bend to read as a curve
constexpr float kLeafCup = 0.18f;     // blade edges rise by this fraction of the half width
constexpr float kSunRadiance = 1.5f;  // radiance of all lights together (before exposure)
const Vec3 kLightColor(1.0f, 0.96f, 0.9f);
const Vec3 kSkyAmbient(0.20f, 0.23f, 0.28f);
const Vec3 kGroundAmbient(0.09f, 0.085f, 0.07f);
const Vec3 kHighlightColor(1.0f, 0.55f, 0.12f);
const Vec3 kAttractColor(0.2f, 0.8f, 0.3f);
const Vec3 kRepelColor(0.9f, 0.2f, 0.15f);

// Texture units.
constexpr GLint kShadowUnit = 0;
constexpr GLint kBarkUnit = 1;
constexpr GLint kLeafUnit = 2;

float linearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

// Template triangles of one branch instance, counter-clockwise seen from outside (see the
// vertex layout in kBranchVertex): the sides, and separately the two caps, which only the
// few instances at chain ends draw.
std::vector<GLushort> branchSideIndices(int n) {
  std::vector<GLushort> idx;
  idx.reserve(size_t(6 * n));
  for (int j = 0; j < n; ++j) {
    int a = j, b = j + 1, c = n + 1 + j + 1, d = n + 1 + j;
    for (int v : {a, b, c, a, c, d}) idx.push_back(GLushort(v));
  }
  return idx;
}

std::vector<GLushort> branchCapIndices(int n) {
  std::vector<GLushort> idx;
  idx.reserve(size_t(6 * n));
  const int startApex = 2 * n + 2, endApex = 2 * n + 3, startRim = 2 * n + 4, endRim = 3 * n + 4;
  for (int j = 0; j < n; ++j) {
    int k = (j + 1) % n;
    for (int v : {startApex, startRim + k, startRim + j, endApex, endRim + j, endRim + k}) idx.push_back(GLushort(v));
  }
  return idx;
}

std::vector<GLushort> leafTemplateIndices(int rows) {
  std::vector<GLushort> idx;
  for (int k = 0; k < rows; ++k)
    for (int c = 0; c < 2; ++c) {
      int a = 3 * k + c, b = a + 1, d = a + 3, e = d + 1;
      for (int v : {a, b, e, a, e, d}) idx.push_back(GLushort(v));
    }
  return idx;
}

// Instance attributes 0..count-1 read vec4s from `buffer` with the given stride, one per instance.
void instanceAttributes(const gl::Buffer& buffer, GLuint first, GLuint count, GLsizei stride) {
  glBindBuffer(GL_ARRAY_BUFFER, buffer.get());
  for (GLuint i = 0; i < count; ++i) {
    glEnableVertexAttribArray(first + i);
    glVertexAttribPointer(first + i, 4, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<const void*>(uintptr_t(16 * i)));
    glVertexAttribDivisor(first + i, 1);
  }
}

GLint uniform(GLuint program, const char* name) { return glGetUniformLocation(program, name); }
void setMat4(GLuint program, const char* name, const Mat4& m) {
  glUniformMatrix4fv(uniform(program, name), 1, GL_FALSE, m.data());  // Eigen is column-major
}
void setVec3(GLuint program, const char* name, const Vec3& v) { glUniform3f(uniform(program, name), v.x(), v.y(), v.z()); }

struct Lighting {
  int count = 0;
  std::array<float, 4 * kMaxLights> vectors{};
  std::array<float, 3 * kMaxLights> colors{};
  int shadowLight = -1;
  Vec3 shadowDirection = Vec3::Zero();  // direction the shadow light travels
};

Lighting setupLights(const std::vector<env::Light>& lights) {
  Lighting l;
  float total = 0.0f;
  for (const env::Light& light : lights) total += std::max(light.intensity, 0.0f);
  if (total <= 0.0f) total = 1.0f;
  for (const env::Light& light : lights) {
    if (l.count == kMaxLights) break;
    if (light.intensity <= 0.0f) continue;
    int i = l.count++;
    if (light.type == env::Light::Type::Directional) {
      Vec3 toward = -light.direction.normalized();
      l.vectors[size_t(4 * i)] = toward.x();
      l.vectors[size_t(4 * i + 1)] = toward.y();
      l.vectors[size_t(4 * i + 2)] = toward.z();
      l.vectors[size_t(4 * i + 3)] = 0.0f;
      if (l.shadowLight < 0) {
        l.shadowLight = i;
        l.shadowDirection = light.direction.normalized();
      }
    } else {
      l.vectors[size_t(4 * i)] = light.position.x();
      l.vectors[size_t(4 * i + 1)] = light.position.y();
      l.vectors[size_t(4 * i + 2)] = light.position.z();
      l.vectors[size_t(4 * i + 3)] = 1.0f;
    }
    Vec3 c = kLightColor * (kSunRadiance * light.intensity / total);
    for (int k = 0; k < 3; ++k) l.colors[size_t(3 * i + k)] = c[k];
  }
  return l;
}

// Orthographic light view fitted to the focus bounds across the light and to the whole scene
// along it (so casters between the light and the focus still cast). Maps to clip space.
Mat4 lightClipFromWorld(const Vec3& direction, const Bounds3& focus, const Bounds3& all) {
  Vec3 f = direction.normalized();
  Vec3 up = std::abs(f.y()) > 0.99f ? Vec3(Vec3::UnitZ()) : Vec3(Vec3::UnitY());
  Vec3 r = f.cross(up).normalized(), u = r.cross(f);
  auto corners = [](const Bounds3& b, auto&& fn) {
    for (int k = 0; k < 8; ++k)
      fn(Vec3((k & 1) ? b.max.x() : b.min.x(), (k & 2) ? b.max.y() : b.min.y(), (k & 4) ? b.max.z() : b.min.z()));
  };
  Vec2 lo = Vec2::Constant(std::numeric_limits<float>::max()), hi = -lo;
  corners(focus, [&](const Vec3& p) {
    Vec2 q(r.dot(p), u.dot(p));
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  });
  float zlo = std::numeric_limits<float>::max(), zhi = -zlo;
  corners(all, [&](const Vec3& p) {
    zlo = std::min(zlo, f.dot(p));
    zhi = std::max(zhi, f.dot(p));
  });
  Vec2 centre = 0.5f * (lo + hi);
  Vec2 half = (0.5f * (hi - lo) * 1.04f).cwiseMax(Vec2::Constant(1e-3f));
  float zPad = 0.01f * (zhi - zlo) + 1e-3f;
  zlo -= zPad;
  zhi += zPad;
  Mat4 m = Mat4::Zero();
  m.block<1, 3>(0, 0) = r.transpose() / half.x();
  m(0, 3) = -centre.x() / half.x();
  m.block<1, 3>(1, 0) = u.transpose() / half.y();
  m(1, 3) = -centre.y() / half.y();
  m.block<1, 3>(2, 0) = f.transpose() * (2.0f / (zhi - zlo));
  m(2, 3) = -2.0f * zlo / (zhi - zlo) - 1.0f;
  m(3, 3) = 1.0f;
  return m;
}

struct ObstacleGpu {
  gl::VertexArray vao;
  gl::Buffer vertices;
  gl::Buffer indices;
  GLsizei indexCount = 0;
  uint64_t lastFrame = 0;
};

uint64_t hashMesh(const TriangleMesh& mesh) {
  Hasher h;
  h.add(uint64_t(mesh.positions.size()));
  h.add(mesh.positions.data(), mesh.positions.size() * sizeof(Vec3));
  h.add(uint64_t(mesh.indices.size()));
  h.add(mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  return h.digest();
}

// Positions and indices of `mesh` into a new vertex array (attribute 0).
void uploadMesh(const TriangleMesh& mesh, ObstacleGpu& g) {
  g.vao = gl::makeVertexArray();
  g.vertices = gl::makeBuffer();
  g.indices = gl::makeBuffer();
  glBindVertexArray(g.vao.get());
  glBindBuffer(GL_ARRAY_BUFFER, g.vertices.get());
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.positions.size() * sizeof(Vec3)), mesh.positions.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3), nullptr);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.indices.get());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(mesh.indices.size() * sizeof(uint32_t)), mesh.indices.data(),
               GL_STATIC_DRAW);
  g.indexCount = GLsizei(mesh.indices.size());
}

// A plant primitive mesh on the GPU with this frame's instances of it (from every plant).
struct PrimitiveGpu {
  ObstacleGpu mesh;
  gl::Buffer instances;
  size_t capacity = 0;
  std::vector<PrimitiveInstance> data;
};

}  // namespace

struct Renderer::Impl {
  gl::Program branch, leaf, obstacle, primitive, stroke, line;
  gl::Program branchShadow, leafShadow, obstacleShadow, primitiveShadow, blur;

  gl::VertexArray branchVao, capVao, leafVao, strokeVao, lineVao, emptyVao;
  gl::Buffer branchInstances, capInstances, leafInstances, strokeInstances, lineInstances;
  gl::Buffer branchIndices, capIndices, leafIndices, sphereVertices, sphereIndices;
  size_t branchCapacity = 0, capCapacity = 0, leafCapacity = 0, strokeCapacity = 0, lineCapacity = 0;
  int branchSides = 0;
  GLsizei branchIndexCount = 0, capIndexCount = 0, leafIndexCount = 0, sphereIndexCount = 0;

  TextureLayers leafLayers{mesh::kDefaultLeafTexture, true};
  TextureLayers barkLayers{"builtin:bark", false};
  std::unordered_map<uint64_t, ObstacleGpu> obstacles;
  std::unordered_map<uint64_t, PrimitiveGpu> primitives;  // by mesh content
  uint64_t frame = 0;

  int shadowSize = 0;
  gl::Texture shadowMoments, shadowTemp;
  gl::Renderbuffer shadowDepth;
  gl::Framebuffer shadowFbo, blurFbo;

  std::vector<BranchInstance> branchData;
  std::vector<BranchInstance> capData;  // the instances with a cap to draw
  std::vector<LeafInstance> leafData;
  std::vector<float> strokeData, lineData;
  FrameStats stats;

  Impl();
  void setBranchSides(int n);
  void ensureShadowMap(int size);
  ObstacleGpu& obstacleGpu(const ObstacleView& o);
  void setLighting(GLuint program, const Lighting& lights, const Mat4& shadowFromWorld, const Camera& camera,
                   float exposure) const;
  void drawObstacles(const RenderScene& scene, GLuint program, const Mat4& clipFromWorld, bool colors);
  void drawBranches(GLuint program, const Mat4& clipFromWorld);
  void drawLeaves(GLuint program, const Mat4& clipFromWorld);
  void drawPrimitives(GLuint program, const Mat4& clipFromWorld);
  PrimitiveGpu& primitiveGpu(const TriangleMesh& mesh);
  void shadowPass(const RenderScene& scene, const Mat4& lightClip);
};

Renderer::Impl::Impl() {
  using namespace shaders;
  const std::string lit = kLighting;
  branch = gl::makeProgram("branch", "", kBranchVertex, lit + kBranchFragment);
  leaf = gl::makeProgram("leaf", "", kLeafVertex, lit + kLeafFragment);
  obstacle = gl::makeProgram("obstacle", "", kObstacleVertex, lit + kObstacleFragment);
  primitive = gl::makeProgram("primitive", "", kPrimitiveVertex, lit + kPrimitiveFragment);
  stroke = gl::makeProgram("stroke", "", kStrokeVertex, lit + kStrokeFragment);
  line = gl::makeProgram("line", "", kLineVertex, kLineFragment);
  branchShadow = gl::makeProgram("branch shadow", "", kBranchVertex, kMomentsFragment);
  leafShadow = gl::makeProgram("leaf shadow", "#define ALPHA_TEST 1\n", kLeafVertex, kMomentsFragment);
  obstacleShadow = gl::makeProgram("obstacle shadow", "", kObstacleVertex, kMomentsFragment);
  primitiveShadow = gl::makeProgram("primitive shadow", "", kPrimitiveVertex, kMomentsFragment);
  blur = gl::makeProgram("shadow blur", "", kFullscreenVertex, kBlurFragment);

  // Sampler units never change: set them once.
  for (GLuint p : {branch.get(), leaf.get(), obstacle.get(), primitive.get(), stroke.get()}) {
    glUseProgram(p);
    glUniform1i(uniform(p, "uShadowMoments"), kShadowUnit);
    glUniform1i(uniform(p, "uBark"), kBarkUnit);
    glUniform1i(uniform(p, "uLeaves"), kLeafUnit);
  }
  glUseProgram(leafShadow.get());
  glUniform1i(uniform(leafShadow.get(), "uLeaves"), kLeafUnit);
  glUseProgram(blur.get());
  glUniform1i(uniform(blur.get(), "uSource"), 0);
  glUseProgram(0);

  branchInstances = gl::makeBuffer();
  capInstances = gl::makeBuffer();
  leafInstances = gl::makeBuffer();
  strokeInstances = gl::makeBuffer();
  lineInstances = gl::makeBuffer();
  branchIndices = gl::makeBuffer();
  capIndices = gl::makeBuffer();
  leafIndices = gl::makeBuffer();
  sphereVertices = gl::makeBuffer();
  sphereIndices = gl::makeBuffer();

  branchVao = gl::makeVertexArray();
  glBindVertexArray(branchVao.get());
  instanceAttributes(branchInstances, 0, 7, GLsizei(sizeof(BranchInstance)));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, branchIndices.get());
  capVao = gl::makeVertexArray();
  glBindVertexArray(capVao.get());
  instanceAttributes(capInstances, 0, 7, GLsizei(sizeof(BranchInstance)));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, capIndices.get());

  leafVao = gl::makeVertexArray();
  glBindVertexArray(leafVao.get());
  instanceAttributes(leafInstances, 0, 4, GLsizei(sizeof(LeafInstance)));
  std::vector<GLushort> leafIdx = leafTemplateIndices(kLeafRows);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, leafIndices.get());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(leafIdx.size() * sizeof(GLushort)), leafIdx.data(), GL_STATIC_DRAW);
  leafIndexCount = GLsizei(leafIdx.size());

  // Stroke points: a unit icosphere (its positions are its normals).
  TriangleMesh sphere = env::makeSphere(1.0f, 1);
  strokeVao = gl::makeVertexArray();
  glBindVertexArray(strokeVao.get());
  glBindBuffer(GL_ARRAY_BUFFER, sphereVertices.get());
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(sphere.positions.size() * sizeof(Vec3)), sphere.positions.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3), nullptr);
  instanceAttributes(strokeInstances, 1, 2, 8 * sizeof(float));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, sphereIndices.get());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(sphere.indices.size() * sizeof(uint32_t)), sphere.indices.data(),
               GL_STATIC_DRAW);
  sphereIndexCount = GLsizei(sphere.indices.size());

  lineVao = gl::makeVertexArray();
  glBindVertexArray(lineVao.get());
  instanceAttributes(lineInstances, 0, 3, 12 * sizeof(float));

  emptyVao = gl::makeVertexArray();
  glBindVertexArray(0);
}

void Renderer::Impl::setBranchSides(int n) {
  if (n == branchSides) return;
  glBindVertexArray(0);
  auto upload = [](const gl::Buffer& buffer, const std::vector<GLushort>& idx) {
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffer.get());
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(idx.size() * sizeof(GLushort)), idx.data(), GL_STATIC_DRAW);
    return GLsizei(idx.size());
  };
  branchIndexCount = upload(branchIndices, branchSideIndices(n));
  capIndexCount = upload(capIndices, branchCapIndices(n));
  branchSides = n;
}

void Renderer::Impl::ensureShadowMap(int size) {
  if (size == shadowSize) return;
  auto momentsTexture = [&]() {
    gl::Texture t = gl::makeTexture();
    glBindTexture(GL_TEXTURE_2D, t.get());
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, size, size, 0, GL_RG, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
  };
  shadowMoments = momentsTexture();
  shadowTemp = momentsTexture();
  shadowDepth = gl::makeRenderbuffer();
  glBindRenderbuffer(GL_RENDERBUFFER, shadowDepth.get());
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, size, size);

  shadowFbo = gl::makeFramebuffer();
  glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo.get());
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, shadowMoments.get(), 0);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, shadowDepth.get());
  gl::checkFramebuffer(GL_FRAMEBUFFER, "shadow map");
  blurFbo = gl::makeFramebuffer();
  glBindFramebuffer(GL_FRAMEBUFFER, blurFbo.get());
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, shadowTemp.get(), 0);
  gl::checkFramebuffer(GL_FRAMEBUFFER, "shadow blur");
  shadowSize = size;
}

ObstacleGpu& Renderer::Impl::obstacleGpu(const ObstacleView& o) {
  auto [it, added] = obstacles.try_emplace(o.meshKey ? o.meshKey : hashMesh(*o.mesh));
  ObstacleGpu& g = it->second;
  if (added) {
    uploadMesh(*o.mesh, g);
    glBindVertexArray(0);
  }
  g.lastFrame = frame;
  return g;
}

PrimitiveGpu& Renderer::Impl::primitiveGpu(const TriangleMesh& mesh) {
  auto [it, added] = primitives.try_emplace(hashMesh(mesh));
  PrimitiveGpu& g = it->second;
  if (added) {
    uploadMesh(mesh, g.mesh);  // leaves its vertex array bound
    g.instances = gl::makeBuffer();
    instanceAttributes(g.instances, 1, 5, GLsizei(sizeof(PrimitiveInstance)));
    glBindVertexArray(0);
  }
  if (g.mesh.lastFrame != frame) g.data.clear();
  g.mesh.lastFrame = frame;
  return g;
}

void Renderer::Impl::setLighting(GLuint p, const Lighting& lights, const Mat4& shadowFromWorld, const Camera& camera,
                                 float exposure) const {
  glUniform1i(uniform(p, "uLightCount"), lights.count);
  glUniform4fv(uniform(p, "uLightVector"), kMaxLights, lights.vectors.data());
  glUniform3fv(uniform(p, "uLightColor"), kMaxLights, lights.colors.data());
  glUniform1i(uniform(p, "uShadowLight"), shadowSize > 0 ? lights.shadowLight : -1);
  setMat4(p, "uShadowFromWorld", shadowFromWorld);
  setVec3(p, "uSkyAmbient", kSkyAmbient);
  setVec3(p, "uGroundAmbient", kGroundAmbient);
  setVec3(p, "uCameraPos", camera.eye);
  glUniform1f(uniform(p, "uExposure"), exposure);
  setVec3(p, "uHighlightColor", kHighlightColor);
}

void Renderer::Impl::drawObstacles(const RenderScene& scene, GLuint p, const Mat4& clipFromWorld, bool colors) {
  glUseProgram(p);
  setMat4(p, "uClipFromWorld", clipFromWorld);
  for (const ObstacleView& o : scene.obstacles) {
    if (!o.mesh || o.mesh->indices.empty()) continue;
    ObstacleGpu& g = obstacleGpu(o);
    Eigen::Affine3f worldFromLocal = Eigen::Translation3f(o.worldFromLocal.translation) * o.worldFromLocal.rotation;
    setMat4(p, "uWorldFromLocal", worldFromLocal.matrix());
    if (colors) {
      setVec3(p, "uColor", o.color);
      glUniform1f(uniform(p, "uSelected"), o.selected ? 1.0f : 0.0f);
    }
    glBindVertexArray(g.vao.get());
    glDrawElements(GL_TRIANGLES, g.indexCount, GL_UNSIGNED_INT, nullptr);
    ++stats.drawCalls;
  }
}

void Renderer::Impl::drawBranches(GLuint p, const Mat4& clipFromWorld) {
  if (branchData.empty()) return;
  glUseProgram(p);
  setMat4(p, "uClipFromWorld", clipFromWorld);
  glUniform1i(uniform(p, "uSides"), branchSides);
  glBindVertexArray(branchVao.get());
  glDrawElementsInstanced(GL_TRIANGLES, branchIndexCount, GL_UNSIGNED_SHORT, nullptr, GLsizei(branchData.size()));
  ++stats.drawCalls;
  if (!capData.empty()) {
    glBindVertexArray(capVao.get());
    glDrawElementsInstanced(GL_TRIANGLES, capIndexCount, GL_UNSIGNED_SHORT, nullptr, GLsizei(capData.size()));
    ++stats.drawCalls;
  }
}

void Renderer::Impl::drawLeaves(GLuint p, const Mat4& clipFromWorld) {
  if (leafData.empty()) return;
  glUseProgram(p);
  setMat4(p, "uClipFromWorld", clipFromWorld);
  glUniform1i(uniform(p, "uLeafRows"), kLeafRows);
  glUniform1f(uniform(p, "uCup"), kLeafCup);
  glBindVertexArray(leafVao.get());
  glDrawElementsInstanced(GL_TRIANGLES, leafIndexCount, GL_UNSIGNED_SHORT, nullptr, GLsizei(leafData.size()));
  ++stats.drawCalls;
}

void Renderer::Impl::drawPrimitives(GLuint p, const Mat4& clipFromWorld) {
  if (primitives.empty()) return;
  glUseProgram(p);
  setMat4(p, "uClipFromWorld", clipFromWorld);
  for (auto& [key, g] : primitives) {
    if (g.data.empty()) continue;
    glBindVertexArray(g.mesh.vao.get());
    glDrawElementsInstanced(GL_TRIANGLES, g.mesh.indexCount, GL_UNSIGNED_INT, nullptr, GLsizei(g.data.size()));
    ++stats.drawCalls;
  }
}

void Renderer::Impl::shadowPass(const RenderScene& scene, const Mat4& lightClip) {
  // The map is about to be drawn into: make sure no texture unit still holds it.
  glActiveTexture(GL_TEXTURE0 + kShadowUnit);
  glBindTexture(GL_TEXTURE_2D, 0);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, shadowFbo.get());
  glViewport(0, 0, shadowSize, shadowSize);
  glClearColor(1.0f, 1.0f, 0.0f, 0.0f);  // moments of the far plane: lit
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  drawObstacles(scene, obstacleShadow.get(), lightClip, false);
  drawPrimitives(primitiveShadow.get(), lightClip);
  drawBranches(branchShadow.get(), lightClip);
  drawLeaves(leafShadow.get(), lightClip);

  // Separable blur: moments → temp (horizontal), temp → moments (vertical).
  glDisable(GL_DEPTH_TEST);
  glUseProgram(blur.get());
  glBindVertexArray(emptyVao.get());
  glActiveTexture(GL_TEXTURE0);
  const float texel = 1.0f / float(shadowSize);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, blurFbo.get());
  glBindTexture(GL_TEXTURE_2D, shadowMoments.get());
  glUniform2f(uniform(blur.get(), "uStep"), texel, 0.0f);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, shadowFbo.get());
  glBindTexture(GL_TEXTURE_2D, shadowTemp.get());
  glUniform2f(uniform(blur.get(), "uStep"), 0.0f, texel);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  stats.drawCalls += 2;
}

Renderer::Renderer() {
  if (!epoxy_is_desktop_gl() || epoxy_gl_version() < 41) {
    const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    throw Error("OpenGL", "", fmt::format("the renderer needs OpenGL 4.1 core or newer; the current context is {}",
                                          version ? version : "unknown"));
  }
  impl_ = std::make_unique<Impl>();
}

Renderer::~Renderer() = default;

const FrameStats& Renderer::lastFrame() const { return impl_->stats; }

std::string Renderer::glDescription() const {
  auto str = [](GLenum name) {
    const char* s = reinterpret_cast<const char*>(glGetString(name));
    return std::string(s ? s : "?");
  };
  return "OpenGL " + str(GL_VERSION) + ", " + str(GL_RENDERER);
}

void Renderer::render(const RenderScene& scene, const Camera& camera, const RenderSettings& settings, int width,
                      int height) {
  validateCamera(camera, "render");
  validateRenderSettings(settings, "render settings");
  Impl& m = *impl_;
  m.stats = FrameStats{};
  ++m.frame;
  GLint target = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &target);
  GLint viewport[4];
  glGetIntegerv(GL_VIEWPORT, viewport);

  // --- 1. instance data ---
  Timer timer;
  m.branchData.clear();
  m.leafData.clear();
  // Texture layers first, here on the GL thread (a lookup may load a texture); then every
  // plant's branch and leaf instances in parallel.
  std::vector<PlantMaterial> materials(scene.plants.size());
  for (size_t i = 0; i < scene.plants.size(); ++i) {
    if (!scene.plants[i].model) continue;
    const plant::PlantModel& model = *scene.plants[i].model;
    PlantMaterial& mat = materials[i];
    mat.barkLayer = m.barkLayers.layer(model.bark.texture.empty() ? "builtin:bark" : model.bark.texture);
    mat.barkMean = m.barkLayers.meanColor(mat.barkLayer);
    size_t shapes = mesh::leafShapeCount(model);
    mat.shapeLayer.resize(shapes);
    mat.shapeAspect.resize(shapes);
    mat.shapeTint.resize(shapes);
    for (size_t s = 0; s < shapes; ++s) {
      plant::LeafShape shape = mesh::leafShapeFor(model, s);
      mat.shapeLayer[s] = m.leafLayers.layer(shape.texture);
      mat.shapeAspect[s] = shape.aspect;
      mat.shapeTint[s] = shape.tint;
    }
  }
  buildPlantInstances(scene.plants, materials, m.branchData, m.leafData);
  std::vector<std::vector<PrimitiveInstance>> perMesh;
  for (const PlantView& view : scene.plants) {
    if (!view.model || view.model->primitives.empty()) continue;
    const plant::PlantModel& model = *view.model;
    perMesh.clear();
    appendPrimitiveInstances(view, perMesh);
    for (size_t i = 0; i < perMesh.size(); ++i) {
      if (perMesh[i].empty() || model.meshes[i].mesh.indices.empty()) continue;
      PrimitiveGpu& g = m.primitiveGpu(model.meshes[i].mesh);
      g.data.insert(g.data.end(), perMesh[i].begin(), perMesh[i].end());
      m.stats.primitiveInstances += perMesh[i].size();
    }
  }
  m.strokeData.clear();
  for (const env::Stroke& s : scene.strokes) {
    Vec3 c = s.attract ? kAttractColor : kRepelColor;
    float r = std::clamp(0.1f * s.radius, 0.005f, 0.04f);
    for (const Vec3& p : s.points)
      m.strokeData.insert(m.strokeData.end(), {p.x(), p.y(), p.z(), r, c.x(), c.y(), c.z(), 1.0f});
  }
  m.lineData.clear();
  auto addLine = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    m.lineData.insert(m.lineData.end(),
                      {a.x(), a.y(), a.z(), 1.0f, b.x(), b.y(), b.z(), 1.0f, c.x(), c.y(), c.z(), 1.0f});
  };
  if (scene.grid.enabled && scene.grid.spacing > 0.0f && scene.grid.halfLines > 0) {
    const GroundGrid& g = scene.grid;
    float extent = g.spacing * float(g.halfLines);
    float y = g.height + 1e-3f * g.spacing;  // just above a ground plane at the same height
    for (int i = -g.halfLines; i <= g.halfLines; ++i) {
      float t = g.spacing * float(i);
      addLine(Vec3(t, y, -extent), Vec3(t, y, extent), g.color);
      addLine(Vec3(-extent, y, t), Vec3(extent, y, t), g.color);
    }
  }
  for (const GizmoLine& l : scene.gizmos) {
    addLine(l.start, l.end, l.color);
    Vec3 d = l.end - l.start;
    float len = d.norm();
    if (!l.arrow || len <= 0.0f) continue;
    d /= len;
    Vec3 side = d.cross(l.end - camera.eye);
    if (side.squaredNorm() < 1e-12f) side = anyPerpendicular(d);
    side.normalize();
    float head = std::min(0.25f * len, 0.15f);
    addLine(l.end, l.end - head * d + 0.5f * head * side, l.color);
    addLine(l.end, l.end - head * d - 0.5f * head * side, l.color);
  }
  const AirView& air = scene.air;
  const float speedScale = air.maxSpeed > 0.0f ? 1.0f / air.maxSpeed : 0.0f;
  for (size_t i = 0; i < air.positions.size() && i < air.velocities.size(); ++i) {
    const Vec3& v = air.velocities[i];
    const float speed = v.norm();
    const Vec3 along = speed > 0.0f ? Vec3(v / speed) : Vec3::UnitY();
    const Vec3 half = 0.5f * std::max(speed * air.streakSeconds, air.minLength) * along;
    addLine(air.positions[i] - half, air.positions[i] + half, airColor(speed * speedScale));
  }
  m.capData.clear();
  for (const BranchInstance& b : m.branchData)
    if (b.endAxis.w != 0.0f) m.capData.push_back(b);
  m.stats.branchInstances = m.branchData.size();
  m.stats.leafInstances = m.leafData.size();
  m.stats.buildMs = timer.milliseconds();

  // --- uploads ---
  timer.reset();
  m.setBranchSides(settings.branchSides);
  m.barkLayers.sync();
  m.leafLayers.sync();
  glBindVertexArray(0);
  gl::uploadStream(GL_ARRAY_BUFFER, m.branchInstances, m.branchData.data(),
                   m.branchData.size() * sizeof(BranchInstance), m.branchCapacity);
  gl::uploadStream(GL_ARRAY_BUFFER, m.capInstances, m.capData.data(), m.capData.size() * sizeof(BranchInstance),
                   m.capCapacity);
  gl::uploadStream(GL_ARRAY_BUFFER, m.leafInstances, m.leafData.data(), m.leafData.size() * sizeof(LeafInstance),
                   m.leafCapacity);
  gl::uploadStream(GL_ARRAY_BUFFER, m.strokeInstances, m.strokeData.data(), m.strokeData.size() * sizeof(float),
                   m.strokeCapacity);
  gl::uploadStream(GL_ARRAY_BUFFER, m.lineInstances, m.lineData.data(), m.lineData.size() * sizeof(float),
                   m.lineCapacity);
  for (const ObstacleView& o : scene.obstacles)
    if (o.mesh && !o.mesh->indices.empty()) {
      m.obstacleGpu(o);
      m.stats.obstacleTriangles += o.mesh->triangleCount();
    }
  std::erase_if(m.obstacles, [&](const auto& entry) { return entry.second.lastFrame != m.frame; });
  std::erase_if(m.primitives, [&](const auto& entry) { return entry.second.mesh.lastFrame != m.frame; });
  for (auto& [key, g] : m.primitives)
    gl::uploadStream(GL_ARRAY_BUFFER, g.instances, g.data.data(), g.data.size() * sizeof(PrimitiveInstance),
                     g.capacity);
  m.stats.uploadMs = timer.milliseconds();

  // --- 2. shadow pass ---
  timer.reset();
  glActiveTexture(GL_TEXTURE0 + kBarkUnit);
  glBindTexture(GL_TEXTURE_2D_ARRAY, m.barkLayers.texture());
  glActiveTexture(GL_TEXTURE0 + kLeafUnit);
  glBindTexture(GL_TEXTURE_2D_ARRAY, m.leafLayers.texture());
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_FRAMEBUFFER_SRGB);  // shaders write sRGB-encoded values themselves
  glDepthMask(GL_TRUE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);

  Lighting lights = setupLights(effectiveLights(scene));
  Bounds3 all = sceneBounds(scene);
  Mat4 shadowFromWorld = Mat4::Identity();
  bool shadows = settings.shadows && lights.shadowLight >= 0 && !all.empty();
  if (shadows) {
    m.ensureShadowMap(settings.shadowMapSize);
    Bounds3 focus = focusBounds(scene);
    Mat4 lightClip = lightClipFromWorld(lights.shadowDirection, focus, all);
    Mat4 bias = Mat4::Identity();
    bias.block<3, 3>(0, 0) *= 0.5f;
    bias.block<3, 1>(0, 3) = Vec3::Constant(0.5f);
    shadowFromWorld = bias * lightClip;
    m.shadowPass(scene, lightClip);
  } else {
    lights.shadowLight = -1;
  }
  glActiveTexture(GL_TEXTURE0 + kShadowUnit);
  glBindTexture(GL_TEXTURE_2D, shadows ? m.shadowMoments.get() : 0);

  // --- 3. main pass ---
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, GLuint(target));
  glViewport(0, 0, width, height);
  glClearColor(linearToSrgb(scene.background.x()), linearToSrgb(scene.background.y()),
               linearToSrgb(scene.background.z()), 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  const Mat4 clipFromWorld = camera.clipFromWorld(float(width) / float(height));
  for (GLuint p : {m.obstacle.get(), m.primitive.get(), m.branch.get(), m.leaf.get(), m.stroke.get()}) {
    glUseProgram(p);
    m.setLighting(p, lights, shadowFromWorld, camera, settings.exposure);
  }
  glDisable(GL_CULL_FACE);
  m.drawObstacles(scene, m.obstacle.get(), clipFromWorld, true);
  m.drawPrimitives(m.primitive.get(), clipFromWorld);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  m.drawBranches(m.branch.get(), clipFromWorld);
  glDisable(GL_CULL_FACE);
  m.drawLeaves(m.leaf.get(), clipFromWorld);
  if (!m.strokeData.empty()) {
    glUseProgram(m.stroke.get());
    setMat4(m.stroke.get(), "uClipFromWorld", clipFromWorld);
    glBindVertexArray(m.strokeVao.get());
    glDrawElementsInstanced(GL_TRIANGLES, m.sphereIndexCount, GL_UNSIGNED_INT, nullptr,
                            GLsizei(m.strokeData.size() / 8));
    ++m.stats.drawCalls;
  }
  if (!m.lineData.empty()) {
    glUseProgram(m.line.get());
    setMat4(m.line.get(), "uClipFromWorld", clipFromWorld);
    glUniform2f(uniform(m.line.get(), "uViewport"), float(width), float(height));
    glUniform1f(uniform(m.line.get(), "uLineWidth"), settings.lineWidth);
    glBindVertexArray(m.lineVao.get());
    glDrawArraysInstanced(GL_TRIANGLES, 0, 6, GLsizei(m.lineData.size() / 12));
    ++m.stats.drawCalls;
  }
  glBindVertexArray(0);
  glUseProgram(0);
  glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
  m.stats.drawMs = timer.milliseconds();
}

}  // namespace tendril::render
