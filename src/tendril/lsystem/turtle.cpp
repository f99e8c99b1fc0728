#include "tendril/lsystem/turtle.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/env/primitives.h"
#include "tendril/lsystem/derivation.h"
#include "tendril/lsystem/rule_choice.h"

#include <fmt/format.h>

#include <array>
#include <cassert>
#include <cmath>
#include <map>

namespace tendril::lsystem {

namespace {

// Ear clipping is quadratic in a polygon's vertices; ABOP's polygons have a few dozen.
constexpr size_t kMaxPolygonVertices = 256;
// Vertices of polygons, spheres and surfaces per module the string may hold (Limits).
constexpr size_t kPrimitiveVerticesPerModule = 64;
// A surface body is drawn once at compile time; nested surfaces could still multiply.
constexpr size_t kMaxSurfaceVertices = 1'000'000;
constexpr size_t kNotInString = SIZE_MAX;

enum class Mode { Build, Query, Surface };

struct State {
  Vec3 pos = Vec3::Zero();
  Vec3 h = Vec3::UnitY(), l = -Vec3::UnitX(), u = Vec3::UnitZ();  // heading, left, up: h × l = u
  float width = 0.1f;
  int color = 0;
  int32_t node = -1;      // the last segment drawn on this branch (leaves attach to it)
  uint16_t order = 0;     // branch order: brackets deep
  bool newChain = true;   // the next segment starts a new branch chain (after [ or a jump)
  bool climbing = false;  // @Climb: segments are flagged kNodeClimbing
  Vec3 tropism = Vec3::Zero();
  float elasticity = 0.0f;
};

struct EnvRequest {
  size_t index;  // module in the string
  QueryKind kind;
  Vec3 pos, heading;
};

// Rotations of the frame (right-handed, positive angles counter-clockwise about the axis).
inline void yaw(State& s, float c, float sn) {  // about U: + turns H toward L (left)
  Vec3 h = s.h;
  s.h = c * h + sn * s.l;
  s.l = c * s.l - sn * h;
}
inline void pitch(State& s, float c, float sn) {  // about L: & turns H toward -U (down)
  Vec3 h = s.h;
  s.h = c * h - sn * s.u;
  s.u = c * s.u + sn * h;
}
inline void roll(State& s, float c, float sn) {  // about H: \ turns L toward U
  Vec3 l = s.l;
  s.l = c * l + sn * s.u;
  s.u = c * s.u - sn * l;
}

class Turtle;

class TurtleSink final : public EmitSink {
 public:
  TurtleSink(Turtle& t, int depth, uint64_t path) : t_(t), depth_(depth), path_(path) {}
  void emit(ModuleId id, const double* params, uint32_t count, uint32_t loc) override;

 private:
  Turtle& t_;
  int depth_;
  uint64_t path_;
  uint32_t emitted_ = 0;
};

class Turtle {
 public:
  Turtle(const Grammar& g, const InterpretOptions& o, const double* globals, Mode mode)
      : g_(g), o_(o), globals_(globals), mode_(mode) {
    const TurtleSettings& t = g.turtle;
    state_.pos = o.start.position;
    Vec3 h = o.start.heading.squaredNorm() > 0.0f ? Vec3(o.start.heading.normalized()) : Vec3(Vec3::UnitY());
    Vec3 u = o.start.up - h * h.dot(o.start.up);
    if (u.squaredNorm() < 1e-10f) u = anyPerpendicular(h);
    state_.h = h;
    state_.u = u.normalized();
    state_.l = state_.u.cross(state_.h);
    state_.width = t.width;
    state_.tropism = t.tropism;
    state_.elasticity = t.elasticity;
    cosAngle_ = std::cos(t.angle);
    sinAngle_ = std::sin(t.angle);
    // Surfaces are plain turtle strings, drawn before the grammar's rules exist.
    hasRules_.assign(g.modules.size(), 0);
    if (mode_ != Mode::Surface && g.hasRules(Section::Interpretation)) {
      const auto& rules = g.candidates[size_t(Section::Interpretation)];
      for (size_t id = 0; id < g.modules.size(); ++id) hasRules_[id] = !rules[id].empty();
      levelFrames_ = size_t(g.maxFrame) * (g.maxGroup + 1) + 1;
      levelStack_ = size_t(g.maxStack) + 1;
      levels_.resize(size_t(g.maxDepth[size_t(Section::Interpretation)]) + 2);
    }
    if (mode_ == Mode::Build) {
      plant_.species = g.name;
      plant_.bark = g.bark;
      plant_.leafShapes = g.leafShapes;
    }
  }

  void walk(const LString& s, LString* writable) {
    writable_ = writable;
    const size_t n = s.size();
    for (size_t i = 0; i < n; ++i) {
      ModuleId id = s.ids[i];
      index_ = i;
      birth_ = s.birth[i];
      if (hasRules_[id]) expand(id, s.paramsOf(i), s.paramCount(i), 1, i, i);
      else apply(id, s.paramsOf(i), s.paramCount(i), i);
    }
  }

  // Room for the segments and leaves the string draws itself (interpretation rules may add
  // more), so that the plant's arrays grow once instead of doubling their way up.
  void reserveFor(const LString& s) {
    std::vector<uint8_t> kind(g_.modules.size(), 0);
    for (size_t id = 0; id < g_.modules.size(); ++id)
      kind[id] = g_.modules[id].op == TurtleOp::Forward ? 1 : g_.modules[id].op == TurtleOp::Leaf ? 2 : 0;
    size_t nodes = 0, leaves = 0;
    for (ModuleId id : s.ids) {
      nodes += kind[id] == 1;
      leaves += kind[id] == 2;
    }
    plant_.reserve(nodes, leaves);
  }

  plant::PlantModel takePlant() {
    for (auto& [c, mesh] : colorMeshes_) {
      plant::PrimitiveMesh pm;
      pm.name = fmt::format("polygons-{}", c);
      pm.color = g_.colors[size_t(c)];
      pm.mesh = std::move(mesh);
      plant_.meshes.push_back(std::move(pm));
      plant_.primitives.push_back({-1, uint32_t(plant_.meshes.size() - 1), Mat4::Identity()});
    }
    colorMeshes_.clear();
    return std::move(plant_);
  }

  std::vector<std::pair<int, TriangleMesh>> takeSurface() {
    std::vector<std::pair<int, TriangleMesh>> out;
    for (auto& [c, mesh] : colorMeshes_) out.emplace_back(c, std::move(mesh));
    return out;
  }

  const std::vector<EnvRequest>& requests() const { return requests_; }

  // An interpretation rule's successor, module by module (depth = rules applied so far).
  void emitted(ModuleId id, const double* params, uint32_t n, uint32_t loc, int depth, uint64_t path) {
    float f[256];
    for (uint32_t k = 0; k < n; ++k) {
      f[k] = float(params[k]);
      if (!std::isfinite(f[k]))
        throw EvalFailure{loc, fmt::format("parameter {} of {} is not a finite number ({:g})", k + 1,
                                           g_.modules[id].name, params[k])};
    }
    if (g_.modules[id].op == TurtleOp::QueryEnvironment)
      if (std::string problem = queryProblem(f[0], int(n)); !problem.empty()) throw EvalFailure{loc, problem};
    if (hasRules_[id]) expand(id, f, n, depth, path, kNotInString);
    else apply(id, f, n, kNotInString);
  }

 private:
  double* frames(int level) {
    std::vector<double>& m = levels_[size_t(level)];
    if (m.empty()) m.assign(levelFrames_ + levelStack_, 0.0);
    return m.data();
  }

  [[noreturn]] void fail(ModuleId id, const float* p, uint32_t n, const std::string& message) const {
    std::string what = index_ == kNotInString ? "" : fmt::format("module {} ", index_);
    std::string module = formatModule(g_, id, p, n);
    throw Error(g_.source, "", fmt::format("interpretation: {}{}: {}", what, module, message));
  }

  // ABOP §1.6 homomorphism: the first interpretation rule that applies replaces the module
  // while drawing, recursively, to the section's maximum depth.
  void expand(ModuleId id, const float* p, uint32_t n, int depth, uint64_t path, size_t stringIndex) {
    const auto& list = g_.candidates[size_t(Section::Interpretation)][id];
    LazyRng rng(RandomKey{o_.seed, o_.plant, path, o_.step, kPurposeInterpretation});
    double* base = frames(depth);
    double* stack = base + levelFrames_;
    const size_t stride = g_.maxFrame;
    size_t slot = 0;
    auto where = [&] {
      return stringIndex == kNotInString
                 ? fmt::format("drawing {} in step {}", formatModule(g_, id, p, n), o_.step)
                 : fmt::format("drawing module {}, {}, in step {}", stringIndex, formatModule(g_, id, p, n), o_.step);
    };
    auto execute = [&](const Production& q, const Program& prog, double* frame, EmitSink* sink) {
      RunContext rc;
      rc.slots = frame;
      rc.globals = const_cast<double*>(globals_);  // interpretation rules never assign globals
      rc.stack = stack;
      rc.rng = &rng;
      rc.sink = sink;
      try {
        return run(prog, rc);
      } catch (const EvalFailure& f) {
        throw ruleError(g_, q, f, where());
      }
    };
    const Production* rule = chooseRule(
        g_, list, rng, members_, weights_,
        [&](const Production& q, size_t s) {
          double* frame = base + stride * s;
          for (int k = 0; k < q.predArity; ++k) frame[q.predSlot + k] = p[k];
          for (uint16_t k = q.paramCount; k < q.frameSize; ++k) frame[k] = 0.0;
          return q.match.empty() || execute(q, q.match, frame, nullptr) != 0.0;
        },
        [&](const Production& q, size_t s) {
          double w = execute(q, q.weight, base + stride * s, nullptr);
          if (!(w >= 0.0) || !std::isfinite(w))
            throw ruleError(g_, q, EvalFailure{0, fmt::format("probability {:g} is not a finite number >= 0", w)},
                            where());
          return w;
        },
        &slot);
    if (!rule) {
      apply(id, p, n, stringIndex);
      return;
    }
    if (depth > g_.maxDepth[size_t(Section::Interpretation)])
      throw Error(g_.source, fmt::format("{}:{}", rule->pos.line, rule->pos.col),
                  fmt::format("interpretation goes deeper than its maximum depth {} (rule `{}` still applies to {}); "
                              "raise `maximum depth:` in the interpretation: section",
                              g_.maxDepth[size_t(Section::Interpretation)], rule->text, formatModule(g_, id, p, n)));
    TurtleSink sink(*this, depth + 1, path);
    execute(*rule, rule->successor, base + stride * slot, &sink);
  }

  void count() {
    if (++interpreted_ > o_.limits.maxModules)
      throw Error(g_.source, "",
                  fmt::format("interpretation draws more than {} modules (the length limit); raise `max length:` or "
                              "lower the interpretation rules' maximum depth",
                              o_.limits.maxModules));
  }

  // cos and sin of a rotation module's angle: its parameter (degrees) or the grammar's angle.
  void angleOr(const float* p, uint32_t n, float* c, float* s) const {
    if (n == 0) {
      *c = cosAngle_;
      *s = sinAngle_;
    } else {
      float a = radians(p[0]);
      *c = std::cos(a);
      *s = std::sin(a);
    }
  }

  Quat frameQuat() const {
    Mat3 m;
    m.col(0) = -state_.l;
    m.col(1) = state_.h;
    m.col(2) = state_.u;
    return Quat(m).normalized();
  }

  void orthonormalize() {
    State& s = state_;
    s.h.normalize();
    s.u = (s.u - s.h * s.h.dot(s.u)).normalized();
    s.l = s.u.cross(s.h);
  }

  // Rotates the whole frame by `angle` about unit `axis` (Rodrigues).
  void rotateFrame(const Vec3& axis, float angle) {
    float c = std::cos(angle), sn = std::sin(angle);
    auto rot = [&](const Vec3& v) { return Vec3(v * c + axis.cross(v) * sn + axis * axis.dot(v) * (1.0f - c)); };
    state_.h = rot(state_.h);
    state_.l = rot(state_.l);
    state_.u = rot(state_.u);
  }

  void forward(ModuleId id, const float* p, uint32_t n, bool draw) {
    State& s = state_;
    float len = n ? p[0] : g_.turtle.step;
    if (polygonDepth_ > 0) {  // inside { }: F and f trace the polygon's edges (ABOP §1.9.2)
      moveTo(id, p, n, s.pos + s.h * len);
      return;
    }
    if (draw) orthonormalize();
    // Growth-Flow (Algorithm 1): a segment, drawn or not, grows shorter and turned toward the
    // wind it grew in; it keeps that once grown. The turtle keeps its still-air frame.
    const plant::GrowthFlowHistory::Factors flow = windFactors();
    Vec3 stillH, stillL, stillU;
    bool turned = false;
    if (flow.active) {
      len *= flow.length;
      if (o_.growthFlow->maxLength > 0.0f) len = std::min(len, o_.growthFlow->maxLength);
      const Quat turn = windTurn(s.h, s.u, s.climbing, flow);
      if (turn.w() < 1.0f) {
        stillH = s.h, stillL = s.l, stillU = s.u;
        turned = true;
        s.h = (turn * s.h).normalized();
        s.l = (turn * s.l).normalized();
        s.u = (turn * s.u).normalized();
        orthonormalize();
      }
    }
    if (!draw) {
      moveTo(id, p, n, s.pos + s.h * len);
      s.newChain = true;  // a gap: the next segment begins a new chain
      if (turned) s.h = stillH, s.l = stillL, s.u = stillU;
      return;
    }
    if (mode_ == Mode::Build) {
      if (!(s.width > 0.0f)) fail(id, p, n, fmt::format("segments need a width > 0, the turtle's is {:g} (set by ! or width:)", s.width));
      if (len < 0.0f) fail(id, p, n, "a segment's length must be >= 0");
      plant::PlantModel::NodeDef d;
      d.position = s.pos;
      d.orientation = frameQuat();
      d.length = len;
      d.radius = 0.5f * s.width * flow.radius;
      d.parent = s.node;
      d.age = float(o_.step - std::min(o_.step, birth_)) * o_.stepTime;
      d.order = s.order;
      d.flags = (s.climbing ? plant::kNodeClimbing : 0u) | (s.newChain && s.node >= 0 ? plant::kNodeBranchStart : 0u);
      s.node = plant_.addNode(d);
    }
    s.newChain = false;
    moveTo(id, p, n, s.pos + s.h * len);
    if (turned) {  // back to the still-air heading (Algorithm 1)
      s.h = stillH;
      s.l = stillL;
      s.u = stillU;
    }
    // ABOP §2.4: after each segment the heading bends toward T by α = e·|H × T|.
    if (s.elasticity != 0.0f) {
      Vec3 axis = s.h.cross(s.tropism);
      float sn = axis.stableNorm();
      if (sn > 1e-9f && std::isfinite(sn)) rotateFrame(axis / sn, s.elasticity * sn);
    }
  }

  void moveTo(ModuleId id, const float* p, uint32_t n, const Vec3& to) {
    if (!isFinite(to)) fail(id, p, n, "the turtle moves out of the range of numbers");
    state_.pos = to;
  }

  void setHeading(ModuleId id, const float* p, uint32_t n) {
    State& s = state_;
    Vec3 h = Vec3(p[0], p[1], p[2]).stableNormalized();
    if (!(h.squaredNorm() > 0.5f)) fail(id, p, n, "the heading must not be zero");
    Vec3 hint = n == 6 ? Vec3(Vec3(p[3], p[4], p[5]).stableNormalized()) : s.u;
    Vec3 u = hint - h * h.dot(hint);
    if (u.squaredNorm() < 1e-12f) {
      // Up parallel to the new heading: keep the old left vector's side.
      u = h.cross(s.l);
      if (u.squaredNorm() < 1e-12f) u = anyPerpendicular(h);
    }
    s.h = h;
    s.u = u.normalized();
    s.l = s.u.cross(s.h);
  }

  int paletteIndex(int c) const {
    int n = int(g_.colors.size());
    return ((c % n) + n) % n;
  }

  // The mesh collecting primitives of colour c, with room for `vertices` more.
  TriangleMesh& colorMesh(int c, size_t vertices) {
    primitiveVertices_ += vertices;
    size_t limit = mode_ == Mode::Surface ? kMaxSurfaceVertices
                                          : kPrimitiveVerticesPerModule * std::max<size_t>(o_.limits.maxModules, 1);
    if (primitiveVertices_ > limit)
      throw Error(g_.source, "",
                  fmt::format("interpretation: polygons, spheres and surfaces make more than {} vertices{}", limit,
                              mode_ == Mode::Surface ? " in one surface" : " (64 per module of max length:)"));
    return colorMeshes_[paletteIndex(c)];
  }

  // A two-sided polygon (ear clipping in its Newell plane).
  void polygon(const std::vector<Vec3>& v) {
    const size_t n = v.size();
    if (n < 3) return;
    Vec3 normal = Vec3::Zero();
    for (size_t i = 0; i < n; ++i) {
      const Vec3& a = v[i];
      const Vec3& b = v[(i + 1) % n];
      normal += Vec3((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()),
                     (a.x() - b.x()) * (a.y() + b.y()));
    }
    float area2 = normal.norm();
    if (!(area2 > 1e-12f) || !std::isfinite(area2)) return;
    normal /= area2;
    Vec3 ax = anyPerpendicular(normal), ay = normal.cross(ax);
    std::vector<Vec2> q(n);
    for (size_t i = 0; i < n; ++i) q[i] = Vec2(v[i].dot(ax), v[i].dot(ay));
    auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
      return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
    };
    std::vector<uint32_t> idx(n);
    for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
    std::vector<std::array<uint32_t, 3>> tris;
    while (idx.size() > 3) {
      size_t m = idx.size();
      bool clipped = false;
      for (size_t k = 0; k < m && !clipped; ++k) {
        uint32_t a = idx[(k + m - 1) % m], b = idx[k], c = idx[(k + 1) % m];
        if (cross(q[a], q[b], q[c]) <= 0.0f) continue;  // reflex or flat corner
        bool inside = false;
        for (uint32_t o : idx) {
          if (o == a || o == b || o == c) continue;
          if (cross(q[a], q[b], q[o]) >= 0.0f && cross(q[b], q[c], q[o]) >= 0.0f && cross(q[c], q[a], q[o]) >= 0.0f) {
            inside = true;
            break;
          }
        }
        if (inside) continue;
        tris.push_back({a, b, c});
        idx.erase(idx.begin() + long(k));
        clipped = true;
      }
      if (!clipped) {  // self-intersecting outline: fan what is left
        for (size_t k = 1; k + 1 < idx.size(); ++k) tris.push_back({idx[0], idx[k], idx[k + 1]});
        idx.clear();
      }
    }
    if (idx.size() == 3) tris.push_back({idx[0], idx[1], idx[2]});
    TriangleMesh& mesh = colorMesh(state_.color, 2 * v.size());
    for (int side = 0; side < 2; ++side) {
      uint32_t base = uint32_t(mesh.positions.size());
      Vec3 nn = side == 0 ? normal : Vec3(-normal);
      for (const Vec3& p : v) {
        mesh.positions.push_back(p);
        mesh.normals.push_back(nn);
      }
      for (const auto& t : tris) {
        mesh.indices.push_back(base + t[0]);
        mesh.indices.push_back(base + (side == 0 ? t[1] : t[2]));
        mesh.indices.push_back(base + (side == 0 ? t[2] : t[1]));
      }
    }
  }

  // Appends `local` (a mesh in the turtle's frame, scaled by `scale`) at the turtle.
  void place(const TriangleMesh& local, int color, float scale) {
    const State& s = state_;
    Mat3 r;
    r.col(0) = -s.l;
    r.col(1) = s.h;
    r.col(2) = s.u;
    TriangleMesh& mesh = colorMesh(color, local.positions.size());
    uint32_t base = uint32_t(mesh.positions.size());
    bool mirror = scale < 0.0f;
    for (size_t i = 0; i < local.positions.size(); ++i) {
      mesh.positions.push_back(s.pos + r * (scale * local.positions[i]));
      if (!isFinite(mesh.positions.back())) throw Error(g_.source, "", "interpretation: a surface or sphere is too large");
      Vec3 nn = local.normals.size() == local.positions.size() ? Vec3(r * local.normals[i]) : Vec3::UnitY();
      mesh.normals.push_back(mirror ? Vec3(-nn) : nn);
    }
    for (size_t k = 0; k + 2 < local.indices.size(); k += 3) {
      mesh.indices.push_back(base + local.indices[k]);
      mesh.indices.push_back(base + local.indices[k + (mirror ? 2 : 1)]);
      mesh.indices.push_back(base + local.indices[k + (mirror ? 1 : 2)]);
    }
  }

  // Growth-Flow factors of the module being drawn (see InterpretOptions::wind).
  plant::GrowthFlowHistory::Factors windFactors() const {
    if (!o_.wind || !o_.growthFlow) return {};
    return o_.wind->organ(birth_, o_.step, *o_.growthFlow);
  }

  // The rotation from a still-air heading h to the one an organ with these factors grew along
  // (Algorithm 1). A climbing shoot (@Climb, its up vector u facing away from its support) is
  // pressed against its support by a wind blowing into it, not turned into it: its heading
  // never dips further toward the support than the still-air heading does.
  static Quat windTurn(const Vec3& h, const Vec3& u, bool climbing, const plant::GrowthFlowHistory::Factors& flow) {
    if (!flow.active || !(flow.angle > 0.0f) || flow.wind.squaredNorm() == 0.0f) return Quat::Identity();
    Vec3 bent = plant::windGrowthDirection(h, flow.wind, flow.angle);
    if (climbing) {
      const float floor = std::min(h.dot(u), 0.0f), below = bent.dot(u) - floor;
      if (below < 0.0f) {
        bent -= below * u;
        if (!(bent.squaredNorm() > 1e-12f)) return Quat::Identity();
        bent.normalize();
      }
    }
    return bent == h ? Quat::Identity() : Quat::FromTwoVectors(h, bent);
  }

  // The direction of the next segment as it will grow (the wind turns it): the heading ?E
  // probes along, so a probe looks where the plant will grow. ?H, ?U and ?L report the
  // still-air frame, the one the grammar's tropisms steer (Algorithm 1).
  Vec3 nextHeading() const {
    const State& s = state_;
    const Vec3 h = s.h.normalized();
    if (!o_.wind || !o_.growthFlow) return h;
    const Quat turn = windTurn(h, s.u.normalized(), s.climbing, o_.wind->organ(o_.step + 1, o_.step, *o_.growthFlow));
    return (turn * h).normalized();
  }

  void leaf(ModuleId id, const float* p, uint32_t n) {
    float size = n > 0 ? p[0] : g_.turtle.step;
    if (!(size > 0.0f)) return;  // a leaf of size 0 is not drawn
    const plant::GrowthFlowHistory::Factors flow = windFactors();
    if (flow.torn) return;  // torn off by a wind above its strength (Algorithm 2)
    size *= flow.leafRadius;
    int shape = n > 1 ? int(std::floor(p[1])) : 0;
    if (shape < 0 || size_t(shape) >= g_.leafShapes.size())
      fail(id, p, n, fmt::format("leaf shape {} does not exist (the grammar has {} leaf shape{}, 0 to {})", shape,
                                 g_.leafShapes.size(), g_.leafShapes.size() == 1 ? "" : "s",
                                 g_.leafShapes.size() - 1));
    float petiole = n > 2 ? p[2] : 0.0f;
    if (petiole < 0.0f) fail(id, p, n, "a petiole length must be >= 0");
    State& s = state_;
    orthonormalize();
    if (s.node < 0) {
      // A leaf before any segment: it hangs on a zero-length segment at the turtle.
      if (!(s.width > 0.0f)) fail(id, p, n, "leaves need a segment to hang on, and segments a width > 0");
      plant::PlantModel::NodeDef d;
      d.position = s.pos;
      d.orientation = frameQuat();
      d.radius = 0.5f * s.width;
      d.age = float(o_.step - std::min(o_.step, birth_)) * o_.stepTime;
      d.order = s.order;
      s.node = plant_.addNode(d);
      s.newChain = false;
    }
    const Quat& nodeRot = plant_.orientation[size_t(s.node)];
    plant::PlantModel::LeafDef leaf;
    leaf.node = s.node;
    leaf.offset = nodeRot.conjugate() * (s.pos - plant_.position[size_t(s.node)]);
    leaf.rotation = (nodeRot.conjugate() * frameQuat()).normalized();
    leaf.size = size;
    leaf.petiole = petiole;
    leaf.thickness = g_.turtle.leafThickness * flow.leafThickness;
    leaf.shape = uint16_t(shape);
    plant_.flags[size_t(s.node)] |= plant::kNodeLeafNode;
    plant_.addLeaf(leaf);
  }

  void query(ModuleId id, const float* p, uint32_t n, size_t stringIndex) {
    if (mode_ != Mode::Query || stringIndex == kNotInString || !writable_) return;
    float* out = writable_->paramsOf(stringIndex);
    const State& s = state_;
    auto put = [&](const Vec3& v) {
      for (int k = 0; k < 3; ++k) out[k] = v[k];
    };
    switch (g_.modules[id].op) {
      case TurtleOp::QueryPosition: put(s.pos); return;
      case TurtleOp::QueryHeading: put(s.h.normalized()); return;
      case TurtleOp::QueryUp: put(s.u.normalized()); return;
      case TurtleOp::QueryLeft: put(s.l.normalized()); return;
      case TurtleOp::QueryEnvironment:
        // The axiom, productions and decompositions that emitted it checked kind and count.
        assert(queryProblem(p[0], int(n)).empty());
        requests_.push_back({stringIndex, QueryKind(int(p[0])), s.pos, nextHeading()});
        return;
      default: return;
    }
  }

  void apply(ModuleId id, const float* p, uint32_t n, size_t stringIndex) {
    count();
    State& s = state_;
    float c = 0.0f, sn = 0.0f;
    switch (g_.modules[id].op) {
      case TurtleOp::None:
      case TurtleOp::Cut: return;
      case TurtleOp::Forward: forward(id, p, n, true); return;
      case TurtleOp::Move: forward(id, p, n, false); return;
      case TurtleOp::TurnLeft: angleOr(p, n, &c, &sn); yaw(s, c, sn); return;
      case TurtleOp::TurnRight: angleOr(p, n, &c, &sn); yaw(s, c, -sn); return;
      case TurtleOp::PitchDown: angleOr(p, n, &c, &sn); pitch(s, c, sn); return;
      case TurtleOp::PitchUp: angleOr(p, n, &c, &sn); pitch(s, c, -sn); return;
      case TurtleOp::RollLeft: angleOr(p, n, &c, &sn); roll(s, c, sn); return;
      case TurtleOp::RollRight: angleOr(p, n, &c, &sn); roll(s, c, -sn); return;
      case TurtleOp::TurnAround:
        s.h = -s.h;
        s.l = -s.l;
        return;
      case TurtleOp::RollHorizontal: {
        // ABOP §1.5: roll about H so that L is horizontal, L = V × H / |V × H| (V up).
        Vec3 l = Vec3::UnitY().cross(s.h);
        if (l.squaredNorm() < 1e-12f) return;
        s.l = l.normalized();
        s.u = s.h.cross(s.l);
        return;
      }
      case TurtleOp::Push: {
        stack_.push_back(s);
        s.order = uint16_t(std::min<int>(s.order + 1, 65535));
        s.newChain = true;
        return;
      }
      case TurtleOp::Pop:
        if (!stack_.empty()) {
          s = stack_.back();
          stack_.pop_back();
        }
        return;
      case TurtleOp::Width: s.width = n ? p[0] : s.width * g_.turtle.widthFactor; return;
      case TurtleOp::Color: s.color = n ? int(std::floor(std::clamp(p[0], -1e6f, 1e6f))) : s.color + 1; return;
      case TurtleOp::PolygonBegin:
        ++polygonDepth_;
        if (mode_ != Mode::Query) polygons_.emplace_back();
        return;
      case TurtleOp::PolygonEnd:
        if (polygonDepth_ == 0) return;
        --polygonDepth_;
        if (mode_ != Mode::Query) {
          std::vector<Vec3> v = std::move(polygons_.back());
          polygons_.pop_back();
          polygon(v);
        }
        return;
      case TurtleOp::Vertex:
        if (mode_ != Mode::Query && !polygons_.empty()) {
          if (polygons_.back().size() >= kMaxPolygonVertices)
            fail(id, p, n, fmt::format("a polygon has more than {} vertices", kMaxPolygonVertices));
          polygons_.back().push_back(s.pos);
        }
        return;
      case TurtleOp::SetHeading: setHeading(id, p, n); return;
      case TurtleOp::MoveTo:
        moveTo(id, p, n, Vec3(p[0], p[1], p[2]));
        s.newChain = true;
        return;
      case TurtleOp::TropismVector: s.tropism = Vec3(p[0], p[1], p[2]); return;
      case TurtleOp::Elasticity: s.elasticity = p[0]; return;
      case TurtleOp::Sphere: {
        if (mode_ == Mode::Query) return;
        float r = n ? p[0] : 0.5f * s.width;
        if (!(r > 0.0f)) return;
        static const TriangleMesh kSphere = [] {
          TriangleMesh m = env::makeSphere(1.0f, 1);
          m.normals = m.positions;  // unit sphere: the normal is the position
          return m;
        }();
        place(kSphere, s.color, r);
        return;
      }
      case TurtleOp::Climbing: s.climbing = p[0] != 0.0f; return;
      case TurtleOp::Leaf:
        if (mode_ == Mode::Build) leaf(id, p, n);
        return;
      case TurtleOp::Surface: {
        if (mode_ == Mode::Query) return;
        const ModuleInfo& m = g_.modules[id];
        if (m.surface < 0 || size_t(m.surface) >= g_.surfaces.size()) return;
        float scale = n ? p[0] : 1.0f;
        if (scale == 0.0f) return;
        // A surface's colours count from the turtle's current colour index.
        for (const auto& [color, mesh] : g_.surfaces[size_t(m.surface)].meshes) place(mesh, s.color + color, scale);
        return;
      }
      case TurtleOp::QueryPosition:
      case TurtleOp::QueryHeading:
      case TurtleOp::QueryUp:
      case TurtleOp::QueryLeft:
      case TurtleOp::QueryEnvironment: query(id, p, n, stringIndex); return;
    }
  }

  friend class TurtleSink;

  const Grammar& g_;
  const InterpretOptions& o_;
  const double* globals_;
  Mode mode_;
  State state_;
  std::vector<State> stack_;
  float cosAngle_ = 1.0f, sinAngle_ = 0.0f;
  std::vector<uint8_t> hasRules_;
  size_t levelFrames_ = 0, levelStack_ = 0;
  std::vector<std::vector<double>> levels_;
  std::vector<const Production*> members_;
  std::vector<double> weights_;
  size_t index_ = 0;
  uint32_t birth_ = 0;
  size_t interpreted_ = 0;
  int polygonDepth_ = 0;
  size_t primitiveVertices_ = 0;
  std::vector<std::vector<Vec3>> polygons_;
  std::map<int, TriangleMesh> colorMeshes_;
  plant::PlantModel plant_;
  LString* writable_ = nullptr;
  std::vector<EnvRequest> requests_;
};

void TurtleSink::emit(ModuleId id, const double* params, uint32_t count, uint32_t loc) {
  t_.emitted(id, params, count, loc, depth_, childPath(path_, emitted_++));
}

// Writes the answer of one ?E query into its parameters (docs/grammar.md, "Environment").
void answer(const EnvRequest& r, float* p, uint32_t n, const env::Environment* env) {
  auto put = [&](uint32_t at, float v) {
    if (at < n) p[at] = v;
  };
  auto putVec = [&](uint32_t at, const Vec3& v) {
    for (uint32_t k = 0; k < 3; ++k) put(at + k, v[int(k)]);
  };
  switch (r.kind) {
    case QueryKind::Surface: {
      float radius = p[1];
      std::optional<env::SurfacePoint> sp;
      if (env && radius > 0.0f && std::isfinite(radius)) sp = env->closestPoint(r.pos, radius);
      put(2, sp ? sp->distance : -1.0f);
      putVec(3, sp ? sp->away : Vec3::Zero());
      return;
    }
    case QueryKind::Hit: {
      float length = p[1];
      std::optional<env::RayHit> hit;
      if (env && length > 0.0f && std::isfinite(length)) hit = env->rayCast(r.pos, r.heading, length);
      Vec3 normal = Vec3::Zero();
      if (hit) normal = hit->normal.dot(r.heading) > 0.0f ? Vec3(-hit->normal) : hit->normal;
      put(2, hit ? hit->t : -1.0f);
      putVec(3, normal);
      return;
    }
    case QueryKind::Light: {
      env::LightSample l;
      if (env) l = env->light(r.pos);
      put(1, l.exposure);
      putVec(2, l.exposure > 0.0f ? l.direction : l.nominal);
      return;
    }
    case QueryKind::Attract: {
      putVec(1, env ? env->attraction(r.pos) : Vec3::Zero());
      put(4, env && env->repelled(r.pos) ? 1.0f : 0.0f);
      return;
    }
    case QueryKind::Facing: {
      // The closest surface the turtle is not growing away from: triangles whose normal lies
      // within `angle` degrees of the heading are ignored (a shoot leaving the ground for a wall).
      float radius = p[1];
      float cosLimit = std::cos(radians(p[2]));
      std::optional<env::SurfacePoint> sp;
      if (env && radius > 0.0f && std::isfinite(radius) && std::isfinite(cosLimit))
        sp = env->closestPointFacing(r.pos, radius, r.heading, cosLimit);
      put(3, sp ? sp->distance : -1.0f);
      putVec(4, sp ? sp->away : Vec3::Zero());
      return;
    }
  }
}

}  // namespace

plant::PlantModel interpret(const Grammar& g, const LString& s, const InterpretOptions& options,
                            const double* globals) {
  Turtle t(g, options, globals, Mode::Build);
  t.reserveFor(s);
  t.walk(s, nullptr);
  return t.takePlant();
}

void fillQueries(const Grammar& g, LString& s, const InterpretOptions& options, const double* globals,
                 const env::Environment* env) {
  if (!g.hasQueries) return;
  Turtle t(g, options, globals, Mode::Query);
  t.walk(s, &s);
  const std::vector<EnvRequest>& requests = t.requests();
  parallelFor(0, requests.size(), [&](size_t k) {
    const EnvRequest& r = requests[k];
    answer(r, s.paramsOf(r.index), s.paramCount(r.index), env);
  }, 16);
}

std::vector<std::pair<int, TriangleMesh>> surfaceMeshes(const Grammar& g, const LString& body) {
  InterpretOptions o;
  Turtle t(g, o, nullptr, Mode::Surface);
  t.walk(body, nullptr);
  return t.takeSurface();
}

}  // namespace tendril::lsystem
