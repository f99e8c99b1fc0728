#include "tendril/graph/expand.h"

#include "tendril/core/error.h"
#include "tendril/core/random.h"
#include "tendril/core/curve.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace tendril::graph {

Mat4 Frame::matrix() const {
  Mat4 m = Mat4::Identity();
  m.topLeftCorner<3, 3>() = scale * rotation.toRotationMatrix();
  m.topRightCorner<3, 1>() = position;
  return m;
}

size_t ITree::countOf(int32_t component) const {
  return static_cast<size_t>(std::count_if(instances.begin(), instances.end(),
                                           [&](const Instance& i) { return i.component == component; }));
}

size_t ITree::countOf(std::string_view name) const {
  int32_t c = graph->find(name);
  return c < 0 ? 0 : countOf(c);
}

std::vector<int32_t> ITree::childrenOf(int32_t instance) const {
  std::vector<int32_t> out;
  for (size_t k = size_t(instance) + 1; k < instances.size(); ++k)
    if (instances[k].parent == instance) out.push_back(int32_t(k));
  return out;
}

float outlineRatio(Outline outline, float x) {
  // Weber & Penn (1995), "Creation and rendering of realistic trees", ShapeRatio; their ratio
  // runs from 1 at the base of the crown to 0 at the top.
  float r = std::clamp(1.0f - x, 0.0f, 1.0f);
  switch (outline) {
    case Outline::None: return 1.0f;
    case Outline::Conical: return 0.2f + 0.8f * r;
    case Outline::Spherical: return 0.2f + 0.8f * std::sin(kPi * r);
    case Outline::Hemispherical: return 0.2f + 0.8f * std::sin(0.5f * kPi * r);
    case Outline::Cylindrical: return 1.0f;
    case Outline::Tapered: return 0.5f + 0.5f * r;
    case Outline::Flame: return r <= 0.7f ? r / 0.7f : (1.0f - r) / 0.3f;
    case Outline::InverseConical: return 1.0f - 0.8f * r;
  }
  return 1.0f;
}

std::vector<SpherePlacement> phiballPlacements(int count, float open, float close, const std::vector<float>& areas) {
  std::vector<SpherePlacement> out(size_t(std::max(count, 0)));
  if (count <= 0) return out;
  // dΦ = 2π/τ (seed 004 sidebar); computed in double so that Φ_i stays exact for large i.
  const double golden = (1.0 + std::sqrt(5.0)) / 2.0;
  const double dPhi = 2.0 * M_PI / golden;
  double total = 0.0;
  for (int i = 0; i < count; ++i) total += areas.empty() ? 1.0 : double(areas[size_t(i)]);
  double c1 = std::cos(double(open)), c2 = std::cos(double(close));
  double before = 0.0;
  for (int i = 0; i < count; ++i) {
    double a = areas.empty() ? 1.0 : double(areas[size_t(i)]);
    double ai = before + 0.5 * a;  // A_i: the objects before i and half of object i
    before += a;
    double cosTheta = total > 0.0 ? c1 - (ai / total) * (c1 - c2) : c1;
    double theta = std::acos(std::clamp(cosTheta, -1.0, 1.0));
    double phi = std::fmod(double(i) * dPhi, 2.0 * M_PI);
    SpherePlacement& s = out[size_t(i)];
    s.theta = float(theta);
    s.phi = float(phi);
    // Children lean toward -Z of the azimuth frame, like branches and Hydra children.
    s.rotation = (Quat(Eigen::AngleAxisf(float(phi), Vec3::UnitY())) *
                  Quat(Eigen::AngleAxisf(-float(theta), Vec3::UnitX())))
                     .normalized();
    s.normal = s.rotation * Vec3::UnitY();
  }
  return out;
}

float phiballRadius(float area, float open, float close) {
  double band = 2.0 * M_PI * (std::cos(double(open)) - std::cos(double(close)));
  if (!(band > 1e-12) || !(area > 0.0f)) return 0.0f;
  return float(std::sqrt(double(area) / band));
}

namespace {

constexpr uint64_t kPurposeParam = purposeId("graph.param");
constexpr uint64_t kPurposeGnarl = purposeId("graph.gnarl");
constexpr const char* kDefaultLeafTexture = "builtin:ovate-0";

Quat rotY(float degrees) { return Quat(Eigen::AngleAxisf(radians(degrees), Vec3::UnitY())); }
Quat rotX(float degrees) { return Quat(Eigen::AngleAxisf(radians(degrees), Vec3::UnitX())); }

// Rotation turning unit direction d toward unit target f by `rate · |d × f|` radians, never past
// f (rate < 0 turns away, never past -f): the tropism of seed 003 eq. 3 / seed 004 "Tropisms".
Quat tropism(const Vec3& d, const Vec3& f, float rate) {
  if (rate == 0.0f) return Quat::Identity();
  Vec3 axis = d.cross(f);
  float sinA = axis.norm();
  if (sinA < 1e-7f) return Quat::Identity();
  float theta = std::atan2(sinA, d.dot(f));
  float angle = rate * sinA;
  angle = rate > 0.0f ? std::min(angle, theta) : std::max(angle, -(kPi - theta));
  return Quat(Eigen::AngleAxisf(angle, axis / sinA));
}

struct Placement {
  Frame frame;
  int32_t iteration = 0, count = 1;
  int32_t anchor = -1;
  float lengthScale = 1.0f;   // Tree branches: branch_length times the outline
  bool continuation = false;  // a stem placed here continues the anchor's chain
  Vec3 direction = Vec3::Zero();  // branches: the branch direction (for deviation)
};

class Expander {
 public:
  Expander(std::shared_ptr<const Graph> graph, const ExpandOptions& options, ITree& out)
      : g_(*graph), out_(out), counts_(graph->components.size(), 0) {
    out_.graph = std::move(graph);
    out_.seed = options.seed;
    out_.evaluator = std::make_shared<ParamEvaluator>(g_.table);
    eval_ = out_.evaluator.get();
    // Components that bound the recursion of each strongly connected component.
    for (size_t c = 0; c < g_.components.size(); ++c) {
      const Component& comp = g_.components[c];
      if (!comp.recursive) continue;
      if (size_t(comp.scc) >= limiters_.size()) limiters_.resize(size_t(comp.scc) + 1);
      if (comp.depth > 0) limiters_[size_t(comp.scc)].push_back(int32_t(c));
    }
    Instance root;
    root.frame = options.placement;
    root.key = mix64(options.seed ^ 0x6772617068726f6full);
    out_.instances.push_back(root);
    root_ = options.placement;
  }

  void run() {
    Placement p;
    p.frame = root_;
    for (size_t l = 0; l < g_.rootLinks.size(); ++l) {
      const Link& link = g_.rootLinks[l];
      if (!allowedByFlags(link.target, p.iteration)) continue;
      int32_t child = create(0, link, uint32_t(l), p);
      expand(child);
    }
  }

 private:
  // --- parameters ---
  EvalVars varsOf(const Instance& i) const {
    EvalVars v;
    v.i = i.iteration;
    v.n = i.count;
    v.t = i.count > 1 ? double(i.iteration) / double(i.count - 1) : 0.0;
    v.depth = i.depth;
    return v;
  }
  RandomKey keyOf(const Instance& i, uint64_t slot = 0) const {
    return RandomKey{out_.seed, uint64_t(i.component + 1), i.key, slot, kPurposeParam};
  }
  float num(const ParamDef& p, const Instance& i, uint64_t slot = 0) const {
    if (p.isConstant()) return float(p.value);
    EvalVars v = varsOf(i);
    return float(eval_->eval(p, v, v.t, keyOf(i, slot)));
  }
  int num_i(const ParamDef& p, const Instance& i) const { return int(num(p, i)); }
  Vec3 vec(const Vec3Param& p, const Instance& i) const {
    if (p.isConstant()) return p.constantValue();
    EvalVars v = varsOf(i);
    return eval_->eval(p, v, v.t, keyOf(i));
  }
  // A stem profile parameter at position s along the stem (its range runs along the stem).
  float along(const ParamDef& p, const Instance& i, float s, uint64_t slot) const {
    if (p.isConstant()) return float(p.value);
    EvalVars v = varsOf(i);
    v.s = s;
    return float(eval_->eval(p, v, s, keyOf(i, slot)));
  }

  int32_t textureIndex(const std::string& spec) {
    auto it = textureIds_.find(spec);
    if (it != textureIds_.end()) return it->second;
    out_.textures.push_back(spec);
    int32_t id = int32_t(out_.textures.size() - 1);
    textureIds_.emplace(spec, id);
    return id;
  }

  bool allowedByFlags(int32_t component, int32_t iteration) const {
    const Component& c = g_.components[size_t(component)];
    if (!c.only.empty() && !std::binary_search(c.only.begin(), c.only.end(), iteration)) return false;
    return !std::binary_search(c.exclude.begin(), c.exclude.end(), iteration);
  }
  bool allowedByDepth(int32_t component) const {
    const Component& c = g_.components[size_t(component)];
    return c.depth == 0 || counts_[size_t(component)] < c.depth;
  }
  // The recursion of `c` has ended on the current path: one of the components bounding it has
  // reached its depth.
  bool recursionEnded(const Component& c) const {
    if (!c.recursive) return true;
    for (int32_t z : limiters_[size_t(c.scc)])
      if (counts_[size_t(z)] >= g_.components[size_t(z)].depth) return true;
    return false;
  }

  // --- fields of the World in effect ---
  Vec3 field(const Vec3Param& p, const WorldItem& w, const Vec3& at) const {
    EvalVars v = w.vars;
    v.x = at.x();
    v.y = at.y();
    v.z = at.z();
    RandomKey k{out_.seed, uint64_t(w.component + 1), out_.instances[size_t(w.instance)].key, 0, kPurposeParam};
    Vec3 f = eval_->eval(p, v, v.t, k);
    float n = f.norm();
    return n > 1e-12f ? Vec3(f / n) : Vec3::Zero();
  }
  Vec3 gravityAt(int32_t world, const Vec3& at) const {
    if (world < 0) return Vec3(0, -1, 0);
    const WorldItem& w = out_.worlds[size_t(world)];
    return w.gravityConstant ? w.gravity : field(g_.components[size_t(w.component)].as<WorldParams>().gravity, w, at);
  }
  Vec3 lightAt(int32_t world, const Vec3& at) const {
    if (world < 0) return Vec3(0, 1, 0);
    const WorldItem& w = out_.worlds[size_t(world)];
    return w.lightConstant ? w.light : field(g_.components[size_t(w.component)].as<WorldParams>().light, w, at);
  }

  // --- instances ---
  int32_t create(int32_t parent, const Link& link, uint32_t linkIndex, const Placement& p) {
    if (out_.instances.size() >= g_.maxInstances)
      throw Error(g_.source, "/max_instances",
                  fmt::format("the graph expands to more than {} instances; raise \"max_instances\" or lower counts "
                              "and recursion depths",
                              g_.maxInstances));
    const Instance& par = out_.instances[size_t(parent)];
    const Component& c = g_.components[size_t(link.target)];
    Instance inst;
    inst.component = link.target;
    inst.parent = parent;
    inst.link = link.type;
    inst.iteration = p.iteration;
    inst.count = p.count;
    inst.depth = c.recursive ? counts_[size_t(link.target)] + 1 : par.depth;
    inst.key = mix64(par.key ^ mix64((uint64_t(linkIndex) + 1) * 0x9e3779b97f4a7c15ull + uint64_t(p.iteration) * 0xbf58476d1ce4e5b9ull +
                                     uint64_t(link.target)));
    inst.frame = p.frame;
    inst.lengthScale = p.lengthScale;
    inst.anchor = p.anchor;
    inst.chain = par.chain;
    inst.world = par.world;
    inst.hasColor = par.hasColor;
    inst.color = par.color;
    inst.texture = par.texture;
    out_.instances.push_back(inst);
    continuation_.push_back(p.continuation);
    return int32_t(out_.instances.size() - 1);
  }

  void expand(int32_t id) {
    const Component& c = g_.components[size_t(out_.instances[size_t(id)].component)];
    ++counts_[size_t(out_.instances[size_t(id)].component)];
    {
      Instance& inst = out_.instances[size_t(id)];
      const BasicParams& b = c.basic;
      Frame local;
      local.position = vec(b.translate, inst);
      local.rotation = quatFromEulerDegrees(vec(b.rotate, inst));
      local.scale = num(b.scale, inst);
      inst.frame = inst.frame * local;
      if (b.hasColor) {
        inst.hasColor = true;
        inst.color = vec(b.color, inst);
      }
      if (b.texture) inst.texture = textureIndex(*b.texture);
    }

    // What each kind of link produces here.
    std::vector<Placement> children, branches;
    switch (c.type) {
      case ComponentType::Simple: simple(id, c.as<SimpleParams>(), children); break;
      case ComponentType::Revo: revo(id, c.as<RevoParams>(), children); break;
      case ComponentType::Horn: stem(id, c.as<HornParams>().stem, nullptr, &c.as<HornParams>(), children, branches); break;
      case ComponentType::Tree: stem(id, c.as<TreeParams>().stem, &c.as<TreeParams>(), nullptr, children, branches); break;
      case ComponentType::Leaf: leaf(id, c.as<LeafParams>(), children); break;
      case ComponentType::Hydra: hydra(id, c.as<HydraParams>(), children); break;
      case ComponentType::Wreath: wreath(id, c.as<WreathParams>(), children); break;
      case ComponentType::Phiball: phiball(id, c.as<PhiballParams>(), children); break;
      case ComponentType::Ffd: ffd(id, int32_t(&c - g_.components.data()), c.as<FfdParams>(), children); break;
      case ComponentType::Hyperpatch:
        hyperpatch(id, int32_t(&c - g_.components.data()), c.as<HyperpatchParams>(), children);
        break;
      case ComponentType::World: world(id, int32_t(&c - g_.components.data()), c.as<WorldParams>(), children); break;
    }
    bool branchesHere = c.type == ComponentType::Tree;

    // seed 004 Fig. 3: child links place the target at the parent's geometry, branch links
    // multiply it along a Tree's stem, leaf links of a recursive component wait until the
    // recursion has ended.
    bool ended = recursionEnded(c);
    for (size_t l = 0; l < c.links.size(); ++l) {
      const Link& link = c.links[l];
      if (link.type == LinkType::Leaf && c.recursive && !ended) continue;
      if (!allowedByDepth(link.target)) continue;
      const std::vector<Placement>& where = (link.type == LinkType::Branch && branchesHere) ? branches : children;
      for (const Placement& p : where) {
        if (!allowedByFlags(link.target, p.iteration)) continue;
        int32_t child = create(id, link, uint32_t(l), p);
        expand(child);
      }
    }
    --counts_[size_t(out_.instances[size_t(id)].component)];
  }

  // A single child placement in the instance's own frame, moved by `offset` (instance units).
  Placement single(const Instance& inst, const Vec3& offset = Vec3::Zero()) const {
    Placement p;
    Frame local;
    local.position = offset;
    p.frame = inst.frame * local;
    p.iteration = inst.iteration;
    p.count = inst.count;
    p.anchor = inst.anchor;
    return p;
  }

  // --- geometry-producing components ---
  void simple(int32_t id, const SimpleParams& sp, std::vector<Placement>& children) {
    const Instance inst = out_.instances[size_t(id)];
    Vec3 size = vec(sp.size, inst);
    int segments = num_i(sp.segments, inst);
    if (sp.shape == Shape::Area || sp.shape == Shape::Tube) {
      PointSetItem ps;
      ps.instance = id;
      ps.closed = sp.shape == Shape::Tube;
      ps.caps = sp.caps;
      ps.color = inst.hasColor ? inst.color : Vec3(0.8f, 0.8f, 0.8f);
      ps.texture = inst.texture;
      if (!sp.section.empty()) {
        for (const Vec2& q : sp.section) ps.points.push_back(inst.frame.point(Vec3(q.x(), 0.0f, q.y())));
      } else if (ps.closed) {
        // A circle in the XZ plane, counter-clockwise seen from +Y.
        for (int k = 0; k < segments; ++k) {
          float a = kTwoPi * float(k) / float(segments);
          ps.points.push_back(inst.frame.point(Vec3(0.5f * size.x() * std::cos(a), 0.0f, -0.5f * size.z() * std::sin(a))));
        }
      } else {
        for (int k = 0; k <= segments; ++k)
          ps.points.push_back(inst.frame.point(Vec3(size.x() * (float(k) / float(segments) - 0.5f), 0.0f, 0.0f)));
      }
      // The nearest ancestor's point set continues into this one when they match.
      for (int32_t a = inst.parent; a > 0; a = out_.instances[size_t(a)].parent) {
        int32_t q = out_.instances[size_t(a)].pointSet;
        if (q < 0) continue;
        const PointSetItem& prev = out_.pointSets[size_t(q)];
        if (prev.closed == ps.closed && prev.points.size() == ps.points.size()) ps.predecessor = q;
        break;
      }
      out_.pointSets.push_back(std::move(ps));
      out_.instances[size_t(id)].pointSet = int32_t(out_.pointSets.size() - 1);
    } else {
      ShapeItem s;
      s.instance = id;
      s.kind = ShapeKind::Solid;
      s.shape = sp.shape;
      s.frame = inst.frame;
      s.size = size;
      s.segments = segments;
      s.color = inst.hasColor ? inst.color : Vec3(0.8f, 0.8f, 0.8f);
      s.texture = inst.texture;
      out_.shapes.push_back(s);
    }
    children.push_back(single(inst, Vec3(0.0f, size.y(), 0.0f)));
  }

  void revo(int32_t id, const RevoParams& rp, std::vector<Placement>& children) {
    const Instance inst = out_.instances[size_t(id)];
    ShapeItem s;
    s.instance = id;
    s.kind = ShapeKind::Revo;
    s.frame = inst.frame;
    s.segments = num_i(rp.segments, inst);
    s.samples = num_i(rp.samples, inst);
    s.color = inst.hasColor ? inst.color : Vec3(0.8f, 0.8f, 0.8f);
    s.texture = inst.texture;
    out_.shapes.push_back(s);
    float top = 0.0f;
    for (const Vec2& q : rp.profile) top = std::max(top, q.y());
    children.push_back(single(inst, Vec3(0.0f, top, 0.0f)));
  }

  void leaf(int32_t id, const LeafParams& lp, std::vector<Placement>& children) {
    const Instance inst = out_.instances[size_t(id)];
    LeafItem l;
    l.instance = id;
    float s = inst.frame.scale;
    l.size = num(lp.size, inst) * s;
    l.aspect = num(lp.aspect, inst);
    l.petiole = num(lp.petiole, inst) * s;
    l.thickness = num(lp.thickness, inst) * s;
    l.curvature = radians(num(lp.curvature, inst));
    l.fold = radians(num(lp.fold, inst));
    l.rows = num_i(lp.rows, inst);
    l.columns = num_i(lp.columns, inst);
    Quat q = inst.frame.rotation * rotY(num(lp.roll, inst)) * rotX(num(lp.pitch, inst));
    // seed 004 sidebar, Leaf: the phototropism value "determines how much the local coordinate
    // system of the leaf should be rotated in order to lie perpendicular to a given global light
    // field vector" — the blade's normal turns toward the light by that fraction.
    float photo = num(lp.phototropism, inst);
    if (photo > 0.0f) {
      Vec3 light = lightAt(inst.world, inst.frame.position);
      if (light.squaredNorm() > 0.0f) {
        Quat full = rotationBetween(q * Vec3::UnitZ(), light);
        q = (Quat::Identity().slerp(photo, full) * q).normalized();
      }
    }
    l.frame.rotation = q.normalized();
    l.frame.position = inst.frame.position;
    l.frame.scale = 1.0f;
    l.texture = inst.texture >= 0 ? inst.texture : textureIndex(kDefaultLeafTexture);
    bool textured = !out_.textures[size_t(l.texture)].empty();
    l.mesh = l.curvature != 0.0f || l.fold != 0.0f || !lp.outline.empty() || !textured;
    l.color = inst.hasColor ? inst.color : textured ? Vec3::Ones() : Vec3(0.3f, 0.55f, 0.2f);
    out_.leaves.push_back(l);
    // Children sit at the tip of the (bent) blade, pointing the way the blade ends.
    float k = l.curvature;
    Vec3 midrib = std::abs(k) < 1e-6f ? Vec3(0.0f, 1.0f, 0.0f) : Vec3(0.0f, std::sin(k) / k, (std::cos(k) - 1.0f) / k);
    Placement tip = single(inst);
    tip.frame.rotation = (l.frame.rotation * Quat(Eigen::AngleAxisf(-k, Vec3::UnitX()))).normalized();
    tip.frame.position = l.frame.position + l.frame.rotation * Vec3(0.0f, l.petiole, 0.0f) + l.size * (l.frame.rotation * midrib);
    children.push_back(tip);
  }

  // Horn and Tree stems: segments built by relative transforms (seed 004 sidebar, Horn, Fig. B1)
  // shaped by curvature, twist, gnarl, deviation and tropisms (sidebar, Tree: "The system
  // generates the shape, curvature, deviation, gnarled look, and tropisms of the stem by
  // changing the positions of the triangulated point sets").
  void stem(int32_t id, const StemParams& sp, const TreeParams* tp, const HornParams* hp,
            std::vector<Placement>& children, std::vector<Placement>& branches) {
    const Instance inst = out_.instances[size_t(id)];
    const float scale = inst.frame.scale;
    const int n = num_i(sp.segments, inst);
    const float length = num(sp.length, inst) * scale * inst.lengthScale;
    const float dl = length / float(n);
    const float ds = 1.0f / float(n);
    const bool skeleton = !hp || (hp->primitive == HornPrimitive::Tube && hp->section.empty());
    const bool continuation = continuation_[size_t(id)];

    // Branch positions along the stem (Tree): levels of `whorl` branches each.
    struct Branch {
      float x, azimuth;
      int32_t index;
    };
    std::vector<Branch> plan;
    int branchCount = 0;
    float branchStart = 0, branchEnd = 1;
    if (tp) {
      branchCount = num_i(tp->branches, inst);
      branchStart = num(tp->branchStart, inst);
      branchEnd = num(tp->branchEnd, inst);
      float phyllotaxis = num(tp->phyllotaxis, inst);
      int whorl = num_i(tp->whorl, inst);
      int levels = (branchCount + whorl - 1) / whorl;
      plan.reserve(size_t(branchCount));
      for (int j = 0; j < branchCount; ++j) {
        int level = j / whorl, within = j % whorl;
        float x = levels > 1 ? branchStart + (branchEnd - branchStart) * float(level) / float(levels - 1) : branchStart;
        plan.push_back({x, float(level) * phyllotaxis + float(within) * 360.0f / float(whorl), j});
      }
      // Walked in stem order below (branch_start may lie above branch_end).
      std::stable_sort(plan.begin(), plan.end(), [&](const Branch& a, const Branch& b) {
        return std::min(int(a.x * float(n)), n - 1) < std::min(int(b.x * float(n)), n - 1);
      });
    }

    // The stem starts where it is placed, growing along the frame's +Y.
    Quat q = inst.frame.rotation;
    Vec3 p = inst.frame.position;
    const Quat bend = rotY(num(sp.bendDirection, inst));
    const Quat unbend = bend.conjugate();
    int32_t firstNode = int32_t(out_.nodes.size());
    int32_t stemIndex = int32_t(out_.stems.size());
    if (skeleton) out_.stems.push_back({id, firstNode, n, inst.anchor});
    int32_t firstRing = int32_t(out_.rings.size());

    // A path (Horn): node points resampled evenly along a spline through the given points.
    std::vector<Vec3> pathPoints;
    if (hp && !hp->path.empty()) pathPoints = resamplePath(hp->path, inst.frame, n);

    uint16_t order = 0;
    if (inst.anchor >= 0) order = uint16_t(out_.nodes[size_t(inst.anchor)].order + (continuation ? 0 : 1));
    size_t nextBranch = 0;
    Quat lastQ = q;
    for (int k = 0; k < n; ++k) {
      float s0 = float(k) * ds, sm = (float(k) + 0.5f) * ds;
      float radius = along(sp.radius, inst, s0, uint64_t(k)) * scale;
      Vec3 dir;
      float segLength = dl;
      if (!pathPoints.empty()) {
        Vec3 d = pathPoints[size_t(k) + 1] - pathPoints[size_t(k)];
        segLength = d.norm();
        p = pathPoints[size_t(k)];
        if (segLength > 1e-9f) q = (rotationBetween(q * Vec3::UnitY(), d) * q).normalized();
      }
      dir = q * Vec3::UnitY();
      if (skeleton) {
        StemNode node;
        node.position = p;
        node.orientation = q;
        node.length = segLength;
        node.radius = std::max(radius, 1e-5f);
        node.stem = stemIndex;
        node.order = order;
        if (k == 0) {
          node.parent = inst.anchor;
          if (inst.anchor >= 0 && !continuation) node.flags |= plant::kNodeBranchStart;
        } else {
          node.parent = firstNode + k - 1;
        }
        out_.nodes.push_back(node);
      } else if (hp->primitive == HornPrimitive::Tube) {
        out_.rings.push_back({Frame{q, p, 1.0f}, radius});
      } else {
        // A sequence of primitives (seed 004 sidebar, Horn): one solid per segment.
        ShapeItem s;
        s.instance = id;
        s.kind = ShapeKind::Solid;
        s.shape = hp->primitive == HornPrimitive::Cube       ? Shape::Cube
                  : hp->primitive == HornPrimitive::Sphere   ? Shape::Sphere
                  : hp->primitive == HornPrimitive::Cylinder ? Shape::Cylinder
                  : hp->primitive == HornPrimitive::Cone     ? Shape::Cone
                                                             : Shape::Disc;
        s.frame = Frame{q, p, 1.0f};
        s.size = Vec3(2.0f * radius, segLength, 2.0f * radius);
        s.segments = 12;
        s.color = inst.hasColor ? inst.color : Vec3(0.45f, 0.35f, 0.25f);
        s.texture = inst.texture;
        out_.shapes.push_back(s);
      }
      int32_t anchorHere = skeleton ? firstNode + k : inst.anchor;

      // Branches on this segment (the last segment takes x = 1).
      Vec3 away = Vec3::Zero();
      float deviation = 0.0f;
      while (nextBranch < plan.size() &&
             (std::min(int(plan[nextBranch].x * float(n)), n - 1) <= k)) {
        const Branch& b = plan[nextBranch++];
        EvalVars v = varsOf(inst);
        v.i = b.index;
        v.n = branchCount;
        v.t = branchCount > 1 ? double(b.index) / double(branchCount - 1) : 0.0;
        v.s = b.x;
        RandomKey key = keyOf(inst, uint64_t(b.index) + 1);
        float t = float(v.t);
        float angle = float(eval_->eval(tp->branchAngle, v, t, key));
        float bscale = float(eval_->eval(tp->branchScale, v, t, key));
        float blength = float(eval_->eval(tp->branchLength, v, t, key));
        float roll = float(eval_->eval(tp->branchRoll, v, t, key));
        float dev = float(eval_->eval(tp->deviation, v, t, key));
        float zone = branchEnd > branchStart ? (b.x - branchStart) / (branchEnd - branchStart) : 0.0f;
        blength *= outlineRatio(tp->outline, zone);
        float frac = std::clamp(b.x * float(n) - float(k), 0.0f, 1.0f);
        Placement pl;
        pl.frame.position = p + frac * segLength * dir;
        pl.frame.rotation = (q * rotY(b.azimuth) * rotX(-angle) * rotY(roll)).normalized();
        pl.frame.scale = scale * bscale;
        pl.lengthScale = blength;
        pl.iteration = b.index;
        pl.count = branchCount;
        pl.anchor = anchorHere;
        pl.direction = pl.frame.rotation * Vec3::UnitY();
        away += pl.direction;
        deviation += dev;
        branches.push_back(pl);
      }

      lastQ = q;
      if (pathPoints.empty()) {
        p += segLength * dir;
        // Shape of the next segment: twist and curvature in the stem's frame ...
        float twist = along(sp.twist, inst, sm, uint64_t(k)) * ds;
        float curvature = along(sp.curvature, inst, sm, uint64_t(k)) * ds;
        q = q * rotY(twist) * bend * rotX(-curvature) * unbend;
        // ... gnarl: a random turn about a random axis across the stem ...
        float gnarl = along(sp.gnarl, inst, sm, uint64_t(k));
        if (gnarl > 0.0f) {
          Rng rng(RandomKey{out_.seed, uint64_t(inst.component + 1), inst.key, uint64_t(k), kPurposeGnarl});
          float azimuth = kTwoPi * rng.uniform();
          float angle = radians(gnarl) * rng.uniform(-1.0f, 1.0f);
          Vec3 axis = q * Vec3(std::cos(azimuth), 0.0f, std::sin(azimuth));
          q = Quat(Eigen::AngleAxisf(angle, axis)) * q;
        }
        // ... deviation away from the branches just made ...
        if (deviation != 0.0f && away.squaredNorm() > 1e-12f) {
          Vec3 d = q * Vec3::UnitY();
          Vec3 axis = d.cross(away);
          if (axis.squaredNorm() > 1e-12f) q = Quat(Eigen::AngleAxisf(-radians(deviation), axis.normalized())) * q;
        }
        // ... and the tropisms of the World in effect, each turning the stem toward its field
        // vector in proportion to |d × f| (seed 004 "Tropisms").
        Vec3 mid = p;
        Vec3 d = q * Vec3::UnitY();
        float gravi = along(sp.gravitropism, inst, sm, uint64_t(k));
        float photo = along(sp.phototropism, inst, sm, uint64_t(k));
        if (gravi != 0.0f) q = tropism(d, gravityAt(inst.world, mid), gravi * ds) * q;
        if (photo != 0.0f) q = tropism(q * Vec3::UnitY(), lightAt(inst.world, mid), photo * ds) * q;
        if (inst.world >= 0) {
          const WorldItem& w = out_.worlds[size_t(inst.world)];
          float flex = along(sp.flexibility, inst, sm, uint64_t(k));
          if (w.cylinderStrength > 0.0f && flex > 0.0f)
            q = tropism(q * Vec3::UnitY(), cylinderField(w, mid), w.cylinderStrength * flex * ds) * q;
          float wind = w.wind.norm();
          if (wind > 0.0f && flex > 0.0f) q = tropism(q * Vec3::UnitY(), w.wind / wind, wind * flex * ds) * q;
        }
        q.normalize();
      } else {
        float twist = along(sp.twist, inst, sm, uint64_t(k)) * ds;
        q = (q * rotY(twist)).normalized();
        p = pathPoints[size_t(k) + 1];
      }
    }
    if (!skeleton && hp->primitive == HornPrimitive::Tube) {
      float radius = along(sp.radius, inst, 1.0f, uint64_t(n)) * scale;
      out_.rings.push_back({Frame{lastQ, p, 1.0f}, radius});
      ShapeItem s;
      s.instance = id;
      s.kind = ShapeKind::HornSection;
      s.frame = inst.frame;
      s.firstRing = firstRing;
      s.ringCount = int32_t(out_.rings.size()) - firstRing;
      s.color = inst.hasColor ? inst.color : Vec3(0.45f, 0.35f, 0.25f);
      s.texture = inst.texture;
      out_.shapes.push_back(s);
    }
    Placement tip;
    tip.frame = Frame{lastQ, p, scale};
    tip.iteration = inst.iteration;
    tip.count = inst.count;
    tip.anchor = skeleton ? firstNode + n - 1 : inst.anchor;
    tip.continuation = skeleton;
    children.push_back(tip);
  }

  // Points along a Catmull-Rom spline through `path` (horn frame), n + 1 of them evenly spaced
  // by arc length.
  static std::vector<Vec3> resamplePath(const std::vector<Vec3>& path, const Frame& frame, int n) {
    std::vector<Vec3> pts;
    for (const Vec3& q : path) {
      Vec3 w = frame.point(q);
      if (pts.empty() || (w - pts.back()).norm() > 1e-7f) pts.push_back(w);
    }
    std::vector<Vec3> dense;
    if (pts.size() < 2) {
      dense.assign(2, pts.empty() ? frame.position : pts[0]);
    } else {
      constexpr int kSamples = 32;
      for (size_t k = 0; k + 1 < pts.size(); ++k) {
        Vec3 p0 = k > 0 ? pts[k - 1] : Vec3(2.0f * pts[k] - pts[k + 1]);
        Vec3 p3 = k + 2 < pts.size() ? pts[k + 2] : Vec3(2.0f * pts[k + 1] - pts[k]);
        CurveSegment seg = centripetalCatmullRom(p0, pts[k], pts[k + 1], p3);
        for (int j = 0; j < kSamples; ++j) dense.push_back(seg.point(float(j) / kSamples));
      }
      dense.push_back(pts.back());
    }
    std::vector<float> arc(dense.size(), 0.0f);
    for (size_t k = 1; k < dense.size(); ++k) arc[k] = arc[k - 1] + (dense[k] - dense[k - 1]).norm();
    std::vector<Vec3> out;
    size_t j = 0;
    for (int k = 0; k <= n; ++k) {
      float target = arc.back() * float(k) / float(n);
      while (j + 2 < dense.size() && arc[j + 1] < target) ++j;
      float span = arc[j + 1] - arc[j];
      float f = span > 0.0f ? std::clamp((target - arc[j]) / span, 0.0f, 1.0f) : 0.0f;
      out.push_back(dense[j] + f * (dense[j + 1] - dense[j]));
    }
    return out;
  }

  // The cylindrical tropism (seed 004, Fig. 9b: a philodendron growing around a stick): the
  // field winds around the cylinder's axis at the given pitch and pulls toward its surface.
  static Vec3 cylinderField(const WorldItem& w, const Vec3& at) {
    Vec3 r = at - w.cylinderCenter;
    Vec3 radial = r - r.dot(w.cylinderAxis) * w.cylinderAxis;
    float rho = radial.norm();
    radial = rho > 1e-6f ? Vec3(radial / rho) : anyPerpendicular(w.cylinderAxis);
    Vec3 tangent = w.cylinderAxis.cross(radial);
    Vec3 helix = std::cos(w.cylinderPitch) * tangent + std::sin(w.cylinderPitch) * w.cylinderAxis;
    float pull = std::clamp((rho - w.cylinderRadius) / std::max(w.cylinderRadius, 1e-3f), -1.0f, 1.0f);
    Vec3 f = helix - pull * radial;
    return f.normalized();
  }

  // --- multipliers (seed 004 sidebar, Fig. D) ---
  Placement multiplied(const Instance& inst, const Quat& rotation, const Vec3& offset, float scale, int i,
                       int count) const {
    Placement p;
    Frame local{rotation.normalized(), offset, scale};
    p.frame = inst.frame * local;
    p.iteration = i;
    p.count = count;
    p.anchor = inst.anchor;
    return p;
  }

  // Hydra: children in a star around the axis.
  void hydra(int32_t id, const HydraParams& hp, std::vector<Placement>& children) {
    const Instance inst = out_.instances[size_t(id)];
    int count = num_i(hp.count, inst);
    float offset = num(hp.offset, inst);
    for (int i = 0; i < count; ++i) {
      Instance child = inst;
      child.iteration = i;
      child.count = count;
      float angle = num(hp.angle, child, uint64_t(i) + 1);
      float radius = num(hp.radius, child, uint64_t(i) + 1);
      float scale = num(hp.childScale, child, uint64_t(i) + 1);
      float roll = num(hp.roll, child, uint64_t(i) + 1);
      Quat lean = rotY(offset + 360.0f * float(i) / float(count)) * rotX(-angle);
      children.push_back(multiplied(inst, lean * rotY(roll), radius * (lean * Vec3::UnitY()), scale, i, count));
    }
  }

  // Wreath: children on a circle between the opening and closing angle, like candles.
  void wreath(int32_t id, const WreathParams& wp, std::vector<Placement>& children) {
    const Instance inst = out_.instances[size_t(id)];
    int count = num_i(wp.count, inst);
    float radius = num(wp.radius, inst);
    float open = num(wp.open, inst), close = num(wp.close, inst);
    bool ring = std::abs(close - open) >= 360.0f - 1e-3f;
    float step = count > 0 ? (ring ? (close - open) / float(count) : count > 1 ? (close - open) / float(count - 1) : 0.0f)
                           : 0.0f;
    for (int i = 0; i < count; ++i) {
      Instance child = inst;
      child.iteration = i;
      child.count = count;
      float tilt = num(wp.tilt, child, uint64_t(i) + 1);
      float scale = num(wp.childScale, child, uint64_t(i) + 1);
      Quat around = rotY(open + step * float(i));
      Vec3 position = radius * (around * Vec3(0.0f, 0.0f, -1.0f));
      children.push_back(multiplied(inst, around * rotX(-tilt), position, scale, i, count));
    }
  }

  // Phiball: golden-section placement on a spherical section (sidebar "Golden Section
  // Placement on a Sphere"), children of varying size taking shares of the area.
  void phiball(int32_t id, const PhiballParams& pp, std::vector<Placement>& children) {
    const Instance inst = out_.instances[size_t(id)];
    int count = num_i(pp.count, inst);
    float open = radians(num(pp.open, inst)), close = radians(num(pp.close, inst));
    float influence = num(pp.sizeInfluence, inst);
    float childArea = num(pp.childArea, inst);
    std::vector<float> scales(static_cast<size_t>(count));
    std::vector<float> areas;
    for (int i = 0; i < count; ++i) {
      Instance child = inst;
      child.iteration = i;
      child.count = count;
      scales[size_t(i)] = num(pp.childScale, child, uint64_t(i) + 1);
    }
    if (influence > 0.0f || childArea > 0.0f) {
      areas.resize(size_t(count));
      for (int i = 0; i < count; ++i) {
        float s = std::max(scales[size_t(i)], 0.0f);
        areas[size_t(i)] = std::pow(s, 2.0f * influence);
      }
    }
    float radius = num(pp.radius, inst);
    if (childArea > 0.0f) {
      double total = 0.0;
      for (float a : areas) total += double(a) * childArea;
      radius = phiballRadius(float(total), open, close);
    }
    std::vector<SpherePlacement> spots = phiballPlacements(count, open, close, areas);
    for (int i = 0; i < count; ++i) {
      const SpherePlacement& s = spots[size_t(i)];
      children.push_back(multiplied(inst, s.rotation, radius * s.normal, scales[size_t(i)], i, count));
    }
  }

  // --- global modelling components ---
  int32_t pushChain(int32_t deformer, int32_t next) {
    out_.chains.push_back({deformer, next});
    return int32_t(out_.chains.size() - 1);
  }

  void ffd(int32_t id, int32_t component, const FfdParams& fp, std::vector<Placement>& children) {
    Instance& inst = out_.instances[size_t(id)];
    Deformer d;
    d.instance = id;
    d.component = component;
    d.mode = fp.mode;
    d.frame = inst.frame;
    d.vars = varsOf(inst);
    d.identity = !fp.hasX && !fp.hasY && !fp.hasZ;
    out_.deformers.push_back(std::move(d));
    // seed 004: "FFD components can also switch off the influence of preceding free-form
    // deformations" — the chain starts afresh below a component that does.
    inst.chain = pushChain(int32_t(out_.deformers.size() - 1), fp.disablePrevious ? -1 : inst.chain);
    children.push_back(single(inst));
  }

  void hyperpatch(int32_t id, int32_t component, const HyperpatchParams& hp, std::vector<Placement>& children) {
    const Instance snapshot = out_.instances[size_t(id)];
    Deformer d;
    d.instance = id;
    d.component = component;
    d.mode = hp.mode;
    d.frame = snapshot.frame;
    d.vars = varsOf(snapshot);
    d.degree = hp.degree;
    d.size = hp.size;
    int m = hp.degree + 1;
    d.offsets.assign(size_t(m * m * m), Vec3::Zero());
    for (const HyperpatchParams::Point& pt : hp.points)
      d.offsets[size_t(pt.i + m * (pt.j + m * pt.k))] = vec(pt.offset, snapshot);
    d.identity = std::all_of(d.offsets.begin(), d.offsets.end(), [](const Vec3& o) { return o == Vec3::Zero(); });
    out_.deformers.push_back(std::move(d));
    Instance& inst = out_.instances[size_t(id)];
    inst.chain = pushChain(int32_t(out_.deformers.size() - 1), hp.disablePrevious ? -1 : inst.chain);
    children.push_back(single(inst));
  }

  void world(int32_t id, int32_t component, const WorldParams& wp, std::vector<Placement>& children) {
    const Instance snapshot = out_.instances[size_t(id)];
    WorldItem w;
    w.instance = id;
    w.component = component;
    w.vars = varsOf(snapshot);
    w.gravityConstant = wp.gravity.isConstant();
    w.lightConstant = wp.light.isConstant();
    auto unit = [](const Vec3& v) { return v.norm() > 1e-12f ? Vec3(v.normalized()) : Vec3::Zero(); };
    if (w.gravityConstant) w.gravity = unit(wp.gravity.constantValue());
    if (w.lightConstant) w.light = unit(wp.light.constantValue());
    w.cylinderCenter = wp.cylinderCenter;
    w.cylinderAxis = wp.cylinderAxis;
    w.cylinderRadius = num(wp.cylinderRadius, snapshot);
    w.cylinderStrength = num(wp.cylinderStrength, snapshot);
    w.cylinderPitch = radians(num(wp.cylinderPitch, snapshot));
    float wind = num(wp.wind, snapshot);
    // seed 004: "the influence of wind can be simulated by a horizontal tropism".
    w.wind = wind * (rotY(num(wp.windDirection, snapshot)) * Vec3::UnitX());
    out_.worlds.push_back(w);
    Instance& inst = out_.instances[size_t(id)];
    inst.world = int32_t(out_.worlds.size() - 1);
    children.push_back(single(inst));
  }

  const Graph& g_;
  ITree& out_;
  ParamEvaluator* eval_ = nullptr;
  Frame root_;
  std::vector<int> counts_;                    // instances of each component on the current path
  std::vector<std::vector<int32_t>> limiters_;  // per recursive SCC: components with a depth
  std::vector<uint8_t> continuation_{0};        // per instance: placed to continue a stem
  std::map<std::string, int32_t> textureIds_;
};

}  // namespace

ITree expand(std::shared_ptr<const Graph> graph, const ExpandOptions& options) {
  ITree tree;
  Expander expander(std::move(graph), options, tree);
  expander.run();
  return tree;
}

}  // namespace tendril::graph
