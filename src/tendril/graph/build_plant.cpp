#include "tendril/graph/build_plant.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/graph/deform.h"
#include "tendril/graph/shapes.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

// Deformations and attachment. Every piece of geometry hangs from a skeleton node (its anchor)
// and lies in a chain of deformers (FFD / Hyperpatch instances above it in the i-tree, cut
// where one has disable_previous). Geometry is first moved with the deformers of its own chain
// (inner first), and with its anchor for deformers that act on the anchor but not on it (those
// switched off for it, and "skeleton" deformers for geometry that is not skeleton). Finally it
// is expressed relative to its anchor, whose own deformed frame then carries it: leaves,
// primitives and branches stay attached whatever is switched off (seed 004: "This makes it
// possible to deform stems and twigs of a tree but not the leaves").

namespace tendril::graph {

namespace {

using plant::PlantModel;

struct Pose {
  Vec3 p = Vec3::Zero();
  Quat q = Quat::Identity();
  Pose inverse() const { return {-(q.conjugate() * p), q.conjugate()}; }
  Pose operator*(const Pose& o) const { return {p + q * o.p, (q * o.q).normalized()}; }
  Vec3 point(const Vec3& x) const { return p + q * x; }
};

struct NodeState {
  Vec3 p = Vec3::Zero();
  Quat q = Quat::Identity();
  float length = 0.0f;
  Pose pose() const { return {p, q}; }
};

struct CardState {
  Vec3 p;
  Quat q;
  float size, petiole, aspect;
};

// Appends raw bytes of values to a string: keys for sharing identical meshes and leaf shapes.
struct Key {
  std::string bytes;
  template <class T>
  Key& operator<<(const T& v) {
    bytes.append(reinterpret_cast<const char*>(&v), sizeof(T));
    return *this;
  }
};

class Deformation {
 public:
  explicit Deformation(const ITree& t) : t_(t) {}

  struct Stages {
    std::vector<int32_t> own, anchorOnly, shared;
    bool empty() const { return own.empty() && anchorOnly.empty() && shared.empty(); }
  };

  int32_t chainOfNode(int32_t node) const {
    return node < 0 ? -1 : t_.instances[size_t(t_.stems[size_t(t_.nodes[size_t(node)].stem)].instance)].chain;
  }

  Stages stages(int32_t chain, int32_t anchor) const {
    Stages s;
    if (t_.deformers.empty()) return s;
    std::vector<int32_t> x = chainDeformers(t_, chain);
    std::vector<int32_t> a = chainDeformers(t_, chainOfNode(anchor));
    size_t common = 0;
    while (common < x.size() && common < a.size() && x[x.size() - 1 - common] == a[a.size() - 1 - common]) ++common;
    s.own.assign(x.begin(), x.end() - long(common));
    s.anchorOnly.assign(a.begin(), a.end() - long(common));
    s.shared.assign(x.end() - long(common), x.end());
    return s;
  }

  bool deformsShape(int32_t d, bool skeleton) const {
    return skeleton || t_.deformers[size_t(d)].mode == DeformMode::All;
  }
  // Whether any stage changes the shape of the geometry (else it only rides along).
  bool reshapes(const Stages& s, bool skeleton) const {
    for (int32_t d : s.own)
      if (deformsShape(d, skeleton)) return true;
    for (int32_t d : s.shared)
      if (deformsShape(d, skeleton)) return true;
    return false;
  }

  // A node moved by deformer d: its start and tip are deformed points; it turns by the
  // smallest rotation that takes its old direction to the new one.
  NodeState node(int32_t d, const NodeState& s) const {
    Vec3 dir = s.q * Vec3::UnitY();
    Vec3 a = deformPoint(t_, d, s.p);
    Vec3 b = deformPoint(t_, d, s.p + s.length * dir);
    NodeState out = s;
    out.p = a;
    Vec3 nd = b - a;
    out.length = nd.norm();
    if (out.length > 1e-9f) out.q = (rotationBetween(dir, nd) * s.q).normalized();
    return out;
  }

  // The undeformed frame of a node (identity for no node).
  NodeState rest(int32_t anchor) const {
    if (anchor < 0) return {};
    const StemNode& n = t_.nodes[size_t(anchor)];
    return {n.position, n.orientation, n.length};
  }

  // Runs the stages for geometry hanging from `anchor`; returns the anchor pose the geometry
  // must finally be expressed against.
  template <class ShapeFn, class RigidFn>
  Pose run(const Stages& s, int32_t anchor, bool skeleton, ShapeFn&& shape, RigidFn&& rigid) const {
    NodeState a = rest(anchor);
    for (int32_t d : s.own)
      if (deformsShape(d, skeleton)) shape(d);
    for (int32_t d : s.anchorOnly) {
      NodeState next = node(d, a);
      rigid(next.pose() * a.pose().inverse());
      a = next;
    }
    for (int32_t d : s.shared) {
      NodeState next = node(d, a);
      if (deformsShape(d, skeleton))
        shape(d);
      else
        rigid(next.pose() * a.pose().inverse());
      a = next;
    }
    return a.pose();
  }

 private:
  const ITree& t_;
};

void deformSkeleton(const ITree& t, const Deformation& def, std::vector<NodeState>& nodes) {
  for (const Stem& stem : t.stems) {
    const Instance& inst = t.instances[size_t(stem.instance)];
    Deformation::Stages s = def.stages(inst.chain, stem.anchor);
    Pose anchorRest = def.rest(stem.anchor).pose();
    Pose anchorFinal = stem.anchor >= 0 ? nodes[size_t(stem.anchor)].pose() : Pose();
    bool anchorMoved = stem.anchor >= 0 && (anchorFinal.p != anchorRest.p || anchorFinal.q.coeffs() != anchorRest.q.coeffs());
    if (s.empty() && !anchorMoved) continue;
    auto first = nodes.begin() + stem.firstNode;
    auto last = first + stem.nodeCount;
    auto applyRigid = [&](const Pose& m) {
      for (auto it = first; it != last; ++it) {
        it->p = m.point(it->p);
        it->q = (m.q * it->q).normalized();
      }
    };
    Pose anchorNow = def.run(
        s, stem.anchor, true,
        [&](int32_t d) {
          for (auto it = first; it != last; ++it) *it = def.node(d, *it);
        },
        applyRigid);
    if (stem.anchor >= 0) applyRigid(anchorFinal * anchorNow.inverse());
  }
}

// What a shared primitive mesh is made from.
struct Recipe {
  enum class Kind { Solid, Revo, Blade } kind = Kind::Solid;
  Shape shape = Shape::Cube;
  Vec3 size = Vec3::Ones();
  int segments = 16, samples = 6;
  int32_t component = -1;
  BladeSpec blade;
  plant::PrimitiveMesh out;
};

TriangleMesh cook(const Recipe& r, const ITree& t) {
  switch (r.kind) {
    case Recipe::Kind::Solid: return solidMesh(r.shape, r.size, r.segments);
    case Recipe::Kind::Revo:
      return revoMesh(t.graph->components[size_t(r.component)].as<RevoParams>(), r.samples, r.segments);
    case Recipe::Kind::Blade: return bladeMesh(r.blade);
  }
  return TriangleMesh();
}

// A primitive to place: a shared mesh in a world frame, or a world-space mesh of its own.
struct PrimitiveJob {
  int32_t instance = -1;
  int32_t recipe = -1;  // shared mesh, or -1 for `world`
  Frame frame;
  TriangleMesh world;
  std::string name;
  Vec3 color = Vec3::Ones();
  std::string texture;
};

// The skeleton's nodes (deformed where the graph has deformers) and, where leaves hang from no
// stem, a zero-length root node at the root component's frame (it sweeps to no bark); returns
// that node, or -1.
int32_t addSkeleton(const ITree& t, Deformation& def, PlantModel& plant, const Pose& rootPose) {
  const bool deforming = !t.deformers.empty();
  std::vector<NodeState> nodes(t.nodes.size());
  for (size_t i = 0; i < t.nodes.size(); ++i) nodes[i] = {t.nodes[i].position, t.nodes[i].orientation, t.nodes[i].length};
  if (deforming) deformSkeleton(t, def, nodes);

  size_t cards = 0;
  bool needRoot = false;
  for (const LeafItem& l : t.leaves) {
    if (l.mesh) continue;
    ++cards;
    needRoot = needRoot || t.instances[size_t(l.instance)].anchor < 0;
  }
  plant.reserve(nodes.size() + (needRoot ? 1 : 0), cards);
  for (size_t i = 0; i < nodes.size(); ++i) {
    const StemNode& n = t.nodes[i];
    PlantModel::NodeDef d;
    d.position = nodes[i].p;
    d.orientation = nodes[i].q.normalized();
    d.length = nodes[i].length;
    d.radius = n.radius;
    d.parent = n.parent;
    d.order = n.order;
    d.flags = n.flags;
    plant.addNode(d);
  }
  // Leaves need a node: those hanging from no stem get a zero-length root node (it sweeps to
  // no bark) at the root component's frame.
  int32_t rootNode = -1;
  if (needRoot) {
    PlantModel::NodeDef d;
    d.position = rootPose.p;
    d.orientation = rootPose.q.normalized();
    d.length = 0.0f;
    d.radius = 1e-4f;
    rootNode = plant.addNode(d);
  }
  return rootNode;
}

// Leaves drawn as cards: one leaf shape per (texture, aspect, colour), each card placed on its
// node, following the deformed segment where deformers reshape it.
void addLeafCards(const ITree& t, Deformation& def, int32_t rootNode, const Pose& rootPose, PlantModel& plant) {
  const Graph& g = *t.graph;
  const bool deforming = !t.deformers.empty();
  size_t cards = 0;
  for (const LeafItem& l : t.leaves) cards += l.mesh ? 0 : 1;
  std::vector<int32_t> cardItems;
  cardItems.reserve(cards);
  std::vector<uint16_t> shapeOf;
  shapeOf.reserve(cards);
  std::map<std::string, uint16_t> shapeIds;
  for (size_t i = 0; i < t.leaves.size(); ++i) {
    const LeafItem& l = t.leaves[i];
    if (l.mesh) continue;
    Key k;
    k << l.texture << l.aspect << l.color;
    auto it = shapeIds.find(k.bytes);
    if (it == shapeIds.end()) {
      if (plant.leafShapes.size() >= 65535)
        throw Error(g.source, "", "more than 65535 distinct leaf shapes (texture, aspect and colour combinations)");
      plant::LeafShape shape;
      shape.texture = t.textures[size_t(l.texture)];
      shape.aspect = l.aspect;
      shape.tint = l.color;
      plant.leafShapes.push_back(shape);
      it = shapeIds.emplace(k.bytes, uint16_t(plant.leafShapes.size() - 1)).first;
    }
    cardItems.push_back(int32_t(i));
    shapeOf.push_back(it->second);
  }
  {
    size_t base = plant.leafCount();
    size_t n = cardItems.size();
    plant.leafNode.resize(base + n);
    plant.leafOffset.resize(base + n);
    plant.leafRotation.resize(base + n);
    plant.leafSize.resize(base + n);
    plant.leafThickness.resize(base + n);
    plant.leafPetiole.resize(base + n);
    plant.leafShape.resize(base + n);
    plant.leafMotion.resize(base + n, Vec3::Zero());
    auto place = [&](size_t k) {
      const LeafItem& l = t.leaves[size_t(cardItems[k])];
      int32_t anchor = t.instances[size_t(l.instance)].anchor;
      CardState c{l.frame.position, l.frame.rotation, l.size, l.petiole, l.aspect};
      Pose against = anchor < 0 ? rootPose : def.rest(anchor).pose();
      Deformation::Stages s = def.stages(t.instances[size_t(l.instance)].chain, anchor);
      // Rigid stages move the card with its anchor and cancel out relative to it.
      if (def.reshapes(s, false)) {
        against = def.run(
            s, anchor, false,
            [&](int32_t d) {
              // The card follows the deformed segment from its base to its tip; its width
              // direction follows the deformed width.
              Vec3 y = c.q * Vec3::UnitY(), x = c.q * Vec3::UnitX();
              float reach = c.petiole + c.size;
              Vec3 a = deformPoint(t, d, c.p);
              Vec3 b = deformPoint(t, d, c.p + reach * y);
              Vec3 w = deformPoint(t, d, c.p + 0.5f * c.size * c.aspect * x);
              Vec3 ny = b - a;
              float stretch = ny.norm() / std::max(reach, 1e-9f);
              if (stretch > 1e-6f) {
                Vec3 nx = w - a;
                c.q = frameFromYZ(ny, nx.cross(ny));
                c.size *= stretch;
                c.petiole *= stretch;
              }
              c.p = a;
            },
            [&](const Pose& m) {
              c.p = m.point(c.p);
              c.q = (m.q * c.q).normalized();
            });
        if (anchor < 0) against = rootPose;  // the root node does not move
      }
      Pose rel = against.inverse() * Pose{c.p, c.q};
      size_t slot = base + k;
      plant.leafNode[slot] = anchor >= 0 ? anchor : rootNode;
      plant.leafOffset[slot] = rel.p;
      plant.leafRotation[slot] = rel.q.normalized();
      plant.leafSize[slot] = c.size;
      plant.leafThickness[slot] = l.thickness;
      plant.leafPetiole[slot] = c.petiole;
      plant.leafShape[slot] = shapeOf[k];
    };
    if (deforming) {
      for (size_t k = 0; k < n; ++k) place(k);  // FFD functions are evaluated on one thread
    } else {
      parallelFor(0, n, place, 2048);
    }
    for (size_t k = 0; k < n; ++k) plant.flags[size_t(plant.leafNode[base + k])] |= plant::kNodeLeafNode;
  }
}

// Every primitive of the plant as a job: solids, surfaces of revolution and leaf blades share
// meshes cooked once per recipe; horns and point-set strips are meshes of their own.
struct PrimitivePlan {
  std::vector<Recipe> recipes;
  std::vector<PrimitiveJob> jobs;
};

PrimitivePlan planPrimitives(const ITree& t) {
  const Graph& g = *t.graph;
  PrimitivePlan plan;
  std::vector<Recipe>& recipes = plan.recipes;
  std::vector<PrimitiveJob>& jobs = plan.jobs;
  std::map<std::string, int32_t> recipeIds;
  auto componentName = [&](int32_t instance) {
    int32_t c = t.instances[size_t(instance)].component;
    return c < 0 ? std::string("root") : g.components[size_t(c)].name;
  };
  auto textureOf = [&](int32_t id) { return id < 0 ? std::string() : t.textures[size_t(id)]; };
  auto recipe = [&](Key key, Recipe r, const std::string& name, const Vec3& color, const std::string& texture) {
    key << color;
    key.bytes += texture;
    auto it = recipeIds.find(key.bytes);
    if (it != recipeIds.end()) return it->second;
    r.out.name = name;
    r.out.color = color;
    r.out.texture = texture;
    recipes.push_back(std::move(r));
    return recipeIds.emplace(key.bytes, int32_t(recipes.size() - 1)).first->second;
  };
  for (const ShapeItem& s : t.shapes) {
    PrimitiveJob job;
    job.instance = s.instance;
    job.name = componentName(s.instance);
    job.color = s.color;
    job.texture = textureOf(s.texture);
    job.frame = s.frame;
    Recipe r;
    Key key;
    if (s.kind == ShapeKind::Solid) {
      r.kind = Recipe::Kind::Solid;
      r.shape = s.shape;
      r.size = s.size;
      r.segments = s.segments;
      key << uint8_t(0) << s.shape << s.size << s.segments;
      job.recipe = recipe(key, r, job.name, job.color, job.texture);
    } else if (s.kind == ShapeKind::Revo) {
      r.kind = Recipe::Kind::Revo;
      r.component = t.instances[size_t(s.instance)].component;
      r.samples = s.samples;
      r.segments = s.segments;
      key << uint8_t(1) << r.component << s.samples << s.segments;
      job.recipe = recipe(key, r, job.name, job.color, job.texture);
    } else {
      const HornParams& hp = g.components[size_t(t.instances[size_t(s.instance)].component)].as<HornParams>();
      job.world = sectionSweepMesh(std::span<const Ring>(t.rings.data() + s.firstRing, size_t(s.ringCount)), hp.section);
    }
    jobs.push_back(std::move(job));
  }
  for (const LeafItem& l : t.leaves) {
    if (!l.mesh) continue;
    const LeafParams& lp = g.components[size_t(t.instances[size_t(l.instance)].component)].as<LeafParams>();
    Recipe r;
    r.kind = Recipe::Kind::Blade;
    r.blade.aspect = l.aspect;
    r.blade.curvature = l.curvature;
    r.blade.fold = l.fold;
    r.blade.rows = l.rows;
    r.blade.columns = l.columns;
    r.blade.outline = lp.outline;
    r.blade.outlineSpline = lp.outlineSpline;
    std::string texture = textureOf(l.texture);
    if (lp.outline.empty() && !texture.empty()) r.blade.profile = textureHalfWidths(texture, 64);
    Key key;
    key << uint8_t(2) << t.instances[size_t(l.instance)].component << l.aspect << l.curvature << l.fold << l.rows
        << l.columns;
    PrimitiveJob job;
    job.instance = l.instance;
    job.name = componentName(l.instance);
    job.color = l.color;
    job.texture = texture;
    // The blade mesh has length 1 and starts at the end of the petiole.
    job.frame.rotation = l.frame.rotation;
    job.frame.position = l.frame.position + l.petiole * (l.frame.rotation * Vec3::UnitY());
    job.frame.scale = l.size;
    job.recipe = recipe(key, r, job.name, job.color, job.texture);
    jobs.push_back(std::move(job));
  }
  // Strips between consecutive point sets, and caps where a tube chain starts or ends.
  {
    std::vector<uint8_t> hasSuccessor(t.pointSets.size(), 0);
    std::vector<int> level(t.pointSets.size(), 0);
    for (size_t i = 0; i < t.pointSets.size(); ++i) {
      int32_t pred = t.pointSets[i].predecessor;
      if (pred >= 0) {
        hasSuccessor[size_t(pred)] = 1;
        level[i] = level[size_t(pred)] + 1;
      }
    }
    for (size_t i = 0; i < t.pointSets.size(); ++i) {
      const PointSetItem& ps = t.pointSets[i];
      PrimitiveJob job;
      job.instance = ps.instance;
      job.name = componentName(ps.instance);
      job.color = ps.color;
      job.texture = textureOf(ps.texture);
      if (ps.predecessor >= 0) {
        const PointSetItem& prev = t.pointSets[size_t(ps.predecessor)];
        job.world = pointSetStrip(prev.points, ps.points, ps.closed, float(level[size_t(ps.predecessor)]), float(level[i]));
      }
      bool start = ps.predecessor < 0 && hasSuccessor[i];
      bool end = ps.predecessor >= 0 && !hasSuccessor[i];
      if (ps.closed && ps.caps && (start || end)) job.world.append(pointSetCap(ps.points));
      if (!job.world.empty()) jobs.push_back(std::move(job));
    }
  }
  return plan;
}

// The jobs' meshes: shared ones once, placed by a matrix on their anchor; reshaped ones
// deformed in the world and brought into the anchor's frame.
void addPrimitives(const ITree& t, Deformation& def, PrimitivePlan& plan, PlantModel& plant) {
  std::vector<Recipe>& recipes = plan.recipes;
  std::vector<PrimitiveJob>& jobs = plan.jobs;
  // Shared meshes, cooked in parallel.
  std::vector<TriangleMesh> cooked(recipes.size());
  parallelFor(0, recipes.size(), [&](size_t i) { cooked[i] = cook(recipes[i], t); }, 1);
  std::vector<int32_t> meshOf(recipes.size(), -1);
  for (PrimitiveJob& job : jobs) {
    const Instance& inst = t.instances[size_t(job.instance)];
    int32_t anchor = inst.anchor;
    Deformation::Stages s = def.stages(inst.chain, anchor);
    bool reshaped = def.reshapes(s, false);
    Pose rest = def.rest(anchor).pose();
    if (job.recipe >= 0 && !reshaped) {
      if (cooked[size_t(job.recipe)].empty()) continue;
      if (meshOf[size_t(job.recipe)] < 0) {
        plant::PrimitiveMesh pm = recipes[size_t(job.recipe)].out;
        pm.mesh = cooked[size_t(job.recipe)];
        plant.meshes.push_back(std::move(pm));
        meshOf[size_t(job.recipe)] = int32_t(plant.meshes.size() - 1);
      }
      // Rigid stages cancel out relative to the anchor.
      Frame relative = Frame{rest.q.conjugate(), rest.q.conjugate() * -rest.p, 1.0f} * job.frame;
      plant.primitives.push_back({anchor, uint32_t(meshOf[size_t(job.recipe)]), relative.matrix()});
      continue;
    }
    TriangleMesh world = job.recipe >= 0 ? cooked[size_t(job.recipe)] : std::move(job.world);
    if (world.empty()) continue;
    if (job.recipe >= 0) world.transform(Eigen::Affine3f(job.frame.matrix()));
    Pose against = def.run(
        s, anchor, false,
        [&](int32_t d) {
          for (Vec3& v : world.positions) v = deformPoint(t, d, v);
        },
        [&](const Pose& m) {
          for (Vec3& v : world.positions) v = m.point(v);
        });
    if (reshaped) world.computeNormals();
    Pose toLocal = against.inverse();
    Mat4 m = Mat4::Identity();
    m.topLeftCorner<3, 3>() = toLocal.q.toRotationMatrix();
    m.topRightCorner<3, 1>() = toLocal.p;
    world.transform(Eigen::Affine3f(m));
    plant::PrimitiveMesh pm;
    pm.name = job.name;
    pm.color = job.color;
    pm.texture = job.texture;
    pm.mesh = std::move(world);
    plant.meshes.push_back(std::move(pm));
    plant.primitives.push_back({anchor, uint32_t(plant.meshes.size() - 1), Mat4::Identity()});
  }
}

}  // namespace

PlantModel buildPlant(const ITree& t) {
  const Graph& g = *t.graph;
  PlantModel plant;
  plant.name = g.name;
  plant.species = "graph";
  plant.bark = g.bark;
  Deformation def(t);
  const Pose rootPose{t.instances[0].frame.position, t.instances[0].frame.rotation};
  const int32_t rootNode = addSkeleton(t, def, plant, rootPose);
  addLeafCards(t, def, rootNode, rootPose, plant);
  PrimitivePlan primitives = planPrimitives(t);
  addPrimitives(t, def, primitives, plant);
  plant::validate(plant, g.source);
  return plant;
}

PlantModel generatePlant(std::shared_ptr<const Graph> graph, const ExpandOptions& options) {
  return buildPlant(expand(std::move(graph), options));
}

}  // namespace tendril::graph
