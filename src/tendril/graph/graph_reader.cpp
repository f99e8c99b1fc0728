// Reading graph files (docs/graph-format.md) into a Graph.
#include "tendril/graph/graph.h"

#include "tendril/core/error.h"
#include "tendril/io/texture.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <set>

namespace tendril::graph {

const char* componentTypeName(ComponentType type) {
  switch (type) {
    case ComponentType::Simple: return "simple";
    case ComponentType::Revo: return "revo";
    case ComponentType::Horn: return "horn";
    case ComponentType::Leaf: return "leaf";
    case ComponentType::Tree: return "tree";
    case ComponentType::Hydra: return "hydra";
    case ComponentType::Wreath: return "wreath";
    case ComponentType::Phiball: return "phiball";
    case ComponentType::Ffd: return "ffd";
    case ComponentType::Hyperpatch: return "hyperpatch";
    case ComponentType::World: return "world";
  }
  return "?";
}

const char* shapeName(Shape shape) {
  switch (shape) {
    case Shape::Cube: return "cube";
    case Shape::Sphere: return "sphere";
    case Shape::Cylinder: return "cylinder";
    case Shape::Cone: return "cone";
    case Shape::Disc: return "disc";
    case Shape::Area: return "area";
    case Shape::Tube: return "tube";
  }
  return "?";
}

const char* linkTypeName(LinkType type) {
  switch (type) {
    case LinkType::Child: return "child";
    case LinkType::Branch: return "branch";
    case LinkType::Leaf: return "leaf";
  }
  return "?";
}

int32_t Graph::find(std::string_view name) const {
  for (size_t i = 0; i < components.size(); ++i)
    if (components[i].name == name) return static_cast<int32_t>(i);
  return -1;
}

namespace {

constexpr std::array<std::string_view, 11> kTypeNames = {
    "simple", "revo", "horn", "leaf", "tree", "hydra", "wreath", "phiball", "ffd", "hyperpatch", "world"};

ComponentType readType(JsonObject& o) {
  std::string list;
  for (std::string_view n : kTypeNames) list += (list.empty() ? "" : ", ") + std::string(n);
  if (!o.has("type")) throw o.error("type", "is required: one of " + list);
  std::string s = o.string("type", "");
  for (size_t k = 0; k < kTypeNames.size(); ++k)
    if (kTypeNames[k] == s) return static_cast<ComponentType>(k);
  throw o.error("type", fmt::format("must be one of {}, got \"{}\"", list, s));
}

Shape shapeFromName(const std::string& s) {
  static const std::pair<const char*, Shape> kShapes[] = {{"cube", Shape::Cube},   {"sphere", Shape::Sphere},
                                                          {"cylinder", Shape::Cylinder}, {"cone", Shape::Cone},
                                                          {"disc", Shape::Disc},   {"area", Shape::Area},
                                                          {"tube", Shape::Tube}};
  for (const auto& [name, shape] : kShapes)
    if (s == name) return shape;
  return Shape::Cube;
}

// A texture spec checked now, so that a typo is reported with the graph file's pointer:
// "builtin:<name>", "none" (untextured) or an image file relative to the graph file.
std::string resolveTexture(const std::string& spec, const Location& where, const std::filesystem::path& baseDir) {
  if (spec == "none") return "";
  if (io::isBuiltinTexture(spec)) {
    std::string_view name = std::string_view(spec).substr(io::kBuiltinPrefix.size());
    std::string list;
    for (std::string_view n : io::builtinTextureNames()) {
      if (n == name) return spec;
      list += (list.empty() ? "builtin:" : ", builtin:") + std::string(n);
    }
    throw Error(where.source, where.pointer, fmt::format("unknown built-in texture \"{}\" (known: {})", spec, list));
  }
  if (spec.empty()) throw Error(where.source, where.pointer, "empty texture path (use \"none\" for no texture)");
  std::filesystem::path p(spec);
  if (p.is_relative()) p = baseDir / p;
  p = p.lexically_normal();
  if (!std::filesystem::exists(p))
    throw Error(where.source, where.pointer, fmt::format("texture file {} does not exist", p.string()));
  return p.string();
}

// Degrees and metres: generous bounds that still catch nonsense (and keep floats finite).
constexpr double kMaxLength = 1e4;
constexpr double kMaxAngle = 36000.0;

StemParams readStem(ParamReader& r, double length, int segments, double radius) {
  StemParams s;
  const uint32_t along = kInstanceVars | kVarS;
  s.length = r.scalar("length", length, 0.0, kMaxLength);
  s.segments = r.integer("segments", segments, 1, 10000);
  s.radius = r.scalar("radius", radius, 1e-6, kMaxLength, along);
  s.curvature = r.degrees("curvature", 0.0, -kMaxAngle, kMaxAngle, along);
  s.bendDirection = r.degrees("bend_direction", 0.0, -kMaxAngle, kMaxAngle);
  s.twist = r.degrees("twist", 0.0, -kMaxAngle, kMaxAngle, along);
  s.gnarl = r.degrees("gnarl", 0.0, 0.0, 180.0, along);
  s.gravitropism = r.scalar("gravitropism", 0.0, -100.0, 100.0, along);
  s.phototropism = r.scalar("phototropism", 0.0, -100.0, 100.0, along);
  s.flexibility = r.scalar("flexibility", 1.0, 0.0, 100.0, along);
  return s;
}

SimpleParams readSimple(ParamReader& r) {
  SimpleParams p;
  p.shape = shapeFromName(r.choice("shape", "cube", {"cube", "sphere", "cylinder", "cone", "disc", "area", "tube"}));
  p.size = r.vec3("size", Vec3(0.1f, 0.1f, 0.1f), 0.0, kMaxLength);
  p.segments = r.integer("segments", 16, 3, 1024);
  Location where;
  if (r.has("section") && p.shape != Shape::Area && p.shape != Shape::Tube) {
    r.raw("section", where);
    throw Error(where.source, where.pointer, "\"section\" is only used by the point-set shapes \"area\" and \"tube\"");
  }
  p.section = r.points2("section", p.shape == Shape::Tube ? 3 : 2, -kMaxLength, kMaxLength);
  p.caps = r.boolean("caps", false);
  return p;
}

RevoParams readRevo(ParamReader& r) {
  RevoParams p;
  Location where;
  p.profile = r.points2("profile", 2, -kMaxLength, kMaxLength, &where);
  if (p.profile.empty())  // a small vase
    p.profile = {{0.0f, 0.0f}, {0.08f, 0.0f}, {0.12f, 0.08f}, {0.09f, 0.2f}, {0.07f, 0.26f}, {0.09f, 0.3f}};
  for (size_t k = 0; k < p.profile.size(); ++k)
    if (p.profile[k].x() < 0.0f)
      throw Error(where.source, where.pointer + "/" + std::to_string(k), "profile radii (first numbers) must be >= 0");
  p.spline = r.boolean("spline", true);
  p.samples = r.integer("samples", 6, 1, 64);
  p.segments = r.integer("segments", 24, 3, 1024);
  p.caps = r.boolean("caps", true);
  return p;
}

HornParams readHorn(ParamReader& r) {
  HornParams p;
  p.stem = readStem(r, 0.5, 8, 0.02);
  static const std::pair<const char*, HornPrimitive> kPrims[] = {
      {"tube", HornPrimitive::Tube},         {"cube", HornPrimitive::Cube}, {"sphere", HornPrimitive::Sphere},
      {"cylinder", HornPrimitive::Cylinder}, {"cone", HornPrimitive::Cone}, {"disc", HornPrimitive::Disc}};
  std::string prim = r.choice("primitive", "tube", {"tube", "cube", "sphere", "cylinder", "cone", "disc"});
  for (const auto& [name, value] : kPrims)
    if (prim == name) p.primitive = value;
  Location where;
  if (r.has("section") && p.primitive != HornPrimitive::Tube) {
    r.raw("section", where);
    throw Error(where.source, where.pointer, "\"section\" needs \"primitive\": \"tube\"");
  }
  p.section = r.points2("section", 3, -1e3, 1e3);
  p.path = r.points3("path", 2, -kMaxLength, kMaxLength);
  return p;
}

TreeParams readTree(ParamReader& r) {
  TreeParams p;
  p.stem = readStem(r, 1.0, 12, 0.03);
  const uint32_t branch = kInstanceVars | kVarS;
  p.branches = r.integer("branches", 0, 0, 1000000);
  p.branchStart = r.scalar("branch_start", 0.3, 0.0, 1.0);
  p.branchEnd = r.scalar("branch_end", 1.0, 0.0, 1.0);
  p.branchAngle = r.degrees("branch_angle", 45.0, -kMaxAngle, kMaxAngle, branch);
  p.phyllotaxis = r.degrees("phyllotaxis", 137.50776405003785, -kMaxAngle, kMaxAngle);
  p.whorl = r.integer("whorl", 1, 1, 1000);
  p.branchScale = r.scalar("branch_scale", 1.0, 0.0, 1e3, branch);
  p.branchLength = r.scalar("branch_length", 1.0, 0.0, 1e3, branch);
  p.branchRoll = r.degrees("branch_roll", 0.0, -kMaxAngle, kMaxAngle, branch);
  p.deviation = r.degrees("deviation", 0.0, -180.0, 180.0, branch);
  std::string outline = r.choice("outline", "none", {"none", "conical", "spherical", "hemispherical", "cylindrical",
                                                     "tapered", "flame", "inverse-conical"});
  static const std::pair<const char*, Outline> kOutlines[] = {
      {"none", Outline::None},           {"conical", Outline::Conical},     {"spherical", Outline::Spherical},
      {"hemispherical", Outline::Hemispherical}, {"cylindrical", Outline::Cylindrical}, {"tapered", Outline::Tapered},
      {"flame", Outline::Flame},         {"inverse-conical", Outline::InverseConical}};
  for (const auto& [name, value] : kOutlines)
    if (outline == name) p.outline = value;
  return p;
}

LeafParams readLeaf(ParamReader& r) {
  LeafParams p;
  p.size = r.scalar("size", 0.1, 1e-5, kMaxLength);
  p.aspect = r.scalar("aspect", 1.0, 1e-3, 100.0);
  p.petiole = r.scalar("petiole", 0.0, 0.0, kMaxLength);
  p.curvature = r.degrees("curvature", 0.0, -720.0, 720.0);
  p.fold = r.degrees("fold", 0.0, -180.0, 180.0);
  p.phototropism = r.scalar("phototropism", 0.0, 0.0, 1.0);
  p.roll = r.degrees("roll", 0.0, -kMaxAngle, kMaxAngle);
  p.pitch = r.degrees("pitch", 0.0, -kMaxAngle, kMaxAngle);
  p.thickness = r.scalar("thickness", 0.0003, 0.0, 1.0);
  p.rows = r.integer("rows", 8, 1, 256);
  p.columns = r.integer("columns", 4, 1, 256);
  Location where;
  p.outline = r.points2("outline", 2, -100.0, 100.0, &where);
  for (size_t k = 0; k < p.outline.size(); ++k) {
    const Vec2& q = p.outline[k];
    if (q.x() < 0.0f || q.x() > 1.0f || q.y() < 0.0f)
      throw Error(where.source, where.pointer + "/" + std::to_string(k),
                  "outline points are [position along the blade in 0..1, half width >= 0 in blade lengths]");
    if (k > 0 && !(q.x() > p.outline[k - 1].x()))
      throw Error(where.source, where.pointer + "/" + std::to_string(k),
                  "outline positions along the blade must increase");
  }
  p.outlineSpline = r.boolean("outline_spline", true);
  return p;
}

HydraParams readHydra(ParamReader& r) {
  HydraParams p;
  p.count = r.integer("count", 5, 0, 1000000);
  p.angle = r.degrees("angle", 60.0, -kMaxAngle, kMaxAngle);
  p.radius = r.scalar("radius", 0.0, -kMaxLength, kMaxLength);
  p.offset = r.degrees("offset", 0.0, -kMaxAngle, kMaxAngle);
  p.childScale = r.scalar("child_scale", 1.0, 0.0, 1e3);
  p.roll = r.degrees("roll", 0.0, -kMaxAngle, kMaxAngle);
  return p;
}

WreathParams readWreath(ParamReader& r) {
  WreathParams p;
  p.count = r.integer("count", 8, 0, 1000000);
  p.radius = r.scalar("radius", 0.5, 0.0, kMaxLength);
  p.open = r.degrees("open", 0.0, -kMaxAngle, kMaxAngle);
  p.close = r.degrees("close", 360.0, -kMaxAngle, kMaxAngle);
  p.tilt = r.degrees("tilt", 0.0, -kMaxAngle, kMaxAngle);
  p.childScale = r.scalar("child_scale", 1.0, 0.0, 1e3);
  return p;
}

PhiballParams readPhiball(ParamReader& r) {
  PhiballParams p;
  p.count = r.integer("count", 50, 0, 1000000);
  p.radius = r.scalar("radius", 0.5, 0.0, kMaxLength);
  p.open = r.degrees("open", 0.0, 0.0, 180.0);
  p.close = r.degrees("close", 90.0, 0.0, 180.0);
  p.childScale = r.scalar("child_scale", 1.0, 0.0, 1e3);
  p.sizeInfluence = r.scalar("size_influence", 0.0, 0.0, 1.0);
  p.childArea = r.scalar("child_area", 0.0, 0.0, 1e6);
  return p;
}

DeformMode readMode(ParamReader& r) {
  return r.choice("mode", "all", {"all", "skeleton"}) == "skeleton" ? DeformMode::Skeleton : DeformMode::All;
}

FfdParams readFfd(ParamReader& r) {
  FfdParams p;
  const uint32_t vars = kInstanceVars | kVarXyz;
  // A missing function is the identity.
  p.hasX = r.has("x");
  p.hasY = r.has("y");
  p.hasZ = r.has("z");
  p.x = r.scalar("x", 0.0, -1e6, 1e6, vars);
  p.y = r.scalar("y", 0.0, -1e6, 1e6, vars);
  p.z = r.scalar("z", 0.0, -1e6, 1e6, vars);
  p.mode = readMode(r);
  p.disablePrevious = r.boolean("disable_previous", false);
  return p;
}

HyperpatchParams readHyperpatch(ParamReader& r, ParamTable& table) {
  HyperpatchParams p;
  Location where;
  const Json* degree = r.raw("degree", where);
  if (degree) {
    if (!degree->is_number_integer() || degree->get<int64_t>() < 1 || degree->get<int64_t>() > 4)
      throw Error(where.source, where.pointer,
                  fmt::format("must be an integer in [1, 4] (linear to quartic), got {}", describeJson(*degree)));
    p.degree = int(degree->get<int64_t>());
  }
  std::vector<Vec3> size = {};
  if (const Json* s = r.raw("size", where)) {
    if (!s->is_array() || s->size() != 3)
      throw Error(where.source, where.pointer, fmt::format("expected [x, y, z] in m, got {}", describeJson(*s)));
    for (int k = 0; k < 3; ++k) {
      const Json& e = (*s)[size_t(k)];
      if (!e.is_number() || !(e.get<double>() > 0.0) || e.get<double>() > kMaxLength)
        throw Error(where.source, where.pointer + "/" + std::to_string(k),
                    fmt::format("expected a size > 0 (m), got {}", describeJson(e)));
      p.size[k] = e.get<float>();
    }
  }
  if (const Json* pts = r.raw("points", where)) {
    if (!pts->is_array())
      throw Error(where.source, where.pointer,
                  fmt::format("expected an array of {{\"index\": [i, j, k], \"offset\": [x, y, z]}}, got {}",
                              describeJson(*pts)));
    std::set<std::tuple<int, int, int>> seen;
    for (size_t n = 0; n < pts->size(); ++n) {
      std::string pointer = where.pointer + "/" + std::to_string(n);
      JsonObject o((*pts)[n], where.source, pointer);
      HyperpatchParams::Point pt;
      const Json* idx = o.find("index");
      if (!idx) throw o.error("index", "is required: the control point [i, j, k], each in [0, degree]");
      if (!idx->is_array() || idx->size() != 3)
        throw o.error("index", fmt::format("expected [i, j, k], got {}", describeJson(*idx)));
      int ijk[3];
      for (int k = 0; k < 3; ++k) {
        const Json& e = (*idx)[size_t(k)];
        if (!e.is_number_integer() || e.get<int64_t>() < 0 || e.get<int64_t>() > p.degree)
          throw Error(where.source, o.pointerTo("index") + "/" + std::to_string(k),
                      fmt::format("must be an integer in [0, {}] (the degree), got {}", p.degree, describeJson(e)));
        ijk[k] = int(e.get<int64_t>());
      }
      pt.i = ijk[0];
      pt.j = ijk[1];
      pt.k = ijk[2];
      if (!seen.insert({pt.i, pt.j, pt.k}).second)
        throw o.error("index", fmt::format("control point [{}, {}, {}] is given twice", pt.i, pt.j, pt.k));
      // The offset may use functions of the instance (i, n, t, depth).
      std::map<std::string, const Override*> none;
      ParamReader sub(o, table, "", none);
      if (!o.has("offset")) throw o.error("offset", "is required: the control point's displacement [x, y, z] (m)");
      pt.offset = sub.vec3("offset", Vec3::Zero(), -kMaxLength, kMaxLength);
      o.finish();
      p.points.push_back(std::move(pt));
    }
  }
  p.mode = readMode(r);
  p.disablePrevious = r.boolean("disable_previous", false);
  return p;
}

WorldParams readWorld(ParamReader& r) {
  WorldParams p;
  const uint32_t field = kInstanceVars | kVarXyz;
  p.gravity = r.vec3("gravity", Vec3(0, -1, 0), -1e6, 1e6, field);
  p.light = r.vec3("light", Vec3(0, 1, 0), -1e6, 1e6, field);
  Location where;
  auto fixed = [&](const char* key, const Vec3& fallback, bool direction) {
    const Json* j = r.raw(key, where);
    if (!j) return fallback;
    if (!j->is_array() || j->size() != 3 || !(*j)[0].is_number() || !(*j)[1].is_number() || !(*j)[2].is_number())
      throw Error(where.source, where.pointer, fmt::format("expected [x, y, z], got {}", describeJson(*j)));
    Vec3 v((*j)[0].get<float>(), (*j)[1].get<float>(), (*j)[2].get<float>());
    if (!isFinite(v) || v.cwiseAbs().maxCoeff() > JsonObject::kWorldExtent || (direction && !(v.norm() > 1e-6f)))
      throw Error(where.source, where.pointer,
                  direction ? "must be a non-zero direction" : "must be finite and within 100 km of the origin");
    return direction ? Vec3(v.normalized()) : v;
  };
  p.cylinderCenter = fixed("cylinder_center", Vec3::Zero(), false);
  p.cylinderAxis = fixed("cylinder_axis", Vec3::UnitY(), true);
  p.cylinderRadius = r.scalar("cylinder_radius", 0.05, 0.0, kMaxLength);
  p.cylinderStrength = r.scalar("cylinder_strength", 0.0, 0.0, 1000.0);
  p.cylinderPitch = r.degrees("cylinder_pitch", 20.0, -90.0, 90.0);
  p.wind = r.scalar("wind", 0.0, 0.0, 1000.0);
  p.windDirection = r.degrees("wind_direction", 0.0, -kMaxAngle, kMaxAngle);
  return p;
}

BasicParams readBasic(ParamReader& r, const std::filesystem::path& baseDir) {
  BasicParams b;
  b.translate = r.vec3("translate", Vec3::Zero(), -kMaxLength, kMaxLength);
  b.rotate = r.vec3("rotate", Vec3::Zero(), -kMaxAngle, kMaxAngle);
  b.scale = r.scalar("scale", 1.0, 1e-6, 1e6);
  b.hasColor = r.has("color");
  b.color = r.vec3("color", Vec3(0.8f, 0.8f, 0.8f), 0.0, 1.0);
  Location where;
  if (const Json* t = r.raw("texture", where)) {
    if (!t->is_string())
      throw Error(where.source, where.pointer, fmt::format("expected a texture (\"builtin:<name>\", an image path or "
                                                           "\"none\"), got {}",
                                                           describeJson(*t)));
    b.texture = resolveTexture(t->get<std::string>(), where, baseDir);
  }
  return b;
}

std::vector<int> readFlags(JsonObject& o, std::string_view key) {
  std::vector<int> out;
  const Json* v = o.find(key);
  if (!v) return out;
  if (!v->is_array()) throw o.error(key, fmt::format("expected an array of iteration numbers, got {}", describeJson(*v)));
  for (size_t k = 0; k < v->size(); ++k) {
    const Json& e = (*v)[k];
    if (!e.is_number_integer() || e.get<int64_t>() < 0 || e.get<int64_t>() > 100000000)
      throw Error(o.source(), o.pointerTo(key) + "/" + std::to_string(k),
                  fmt::format("expected an iteration number (an integer >= 0), got {}", describeJson(e)));
    out.push_back(int(e.get<int64_t>()));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<Link> readLinks(JsonObject& o, const std::map<std::string, int32_t>& names, ParamTable& table) {
  std::vector<Link> links;
  const Json* v = o.find("links");
  if (!v) return links;
  if (!v->is_array())
    throw o.error("links", fmt::format("expected an array of links (\"name\" or {{\"to\": \"name\", \"type\": "
                                       "\"child\"}}), got {}",
                                       describeJson(*v)));
  for (size_t k = 0; k < v->size(); ++k) {
    std::string pointer = o.pointerTo("links") + "/" + std::to_string(k);
    const Json& e = (*v)[k];
    Link link;
    std::string target;
    std::string targetPointer = pointer;
    if (e.is_string()) {
      target = e.get<std::string>();
    } else if (e.is_object()) {
      JsonObject lo(e, o.source(), pointer);
      if (!lo.has("to")) throw lo.error("to", "is required: the name of the linked component");
      target = lo.string("to", "");
      targetPointer = lo.pointerTo("to");
      std::string type = lo.choice("type", "child", {"child", "branch", "leaf"});
      link.type = type == "branch" ? LinkType::Branch : type == "leaf" ? LinkType::Leaf : LinkType::Child;
      lo.finish();
    } else {
      throw Error(o.source(), pointer,
                  fmt::format("expected a component name or {{\"to\": \"name\", \"type\": \"child\" | \"branch\" | "
                              "\"leaf\"}}, got {}",
                              describeJson(e)));
    }
    auto it = names.find(target);
    if (it == names.end()) {
      std::string best;
      size_t bestDistance = 3;
      for (const auto& [name, index] : names) {
        size_t d = editDistance(name, target);
        if (d < bestDistance) {
          bestDistance = d;
          best = name;
        }
      }
      throw Error(o.source(), targetPointer,
                  fmt::format("no component named \"{}\"{}", target,
                              best.empty() ? std::string() : fmt::format(" (did you mean \"{}\"?)", best)));
    }
    link.target = it->second;
    link.location = table.addLocation(o.source(), pointer);
    links.push_back(link);
  }
  return links;
}

// Tarjan's strongly connected components over the component links.
void findRecursions(Graph& g) {
  size_t n = g.components.size();
  std::vector<int32_t> index(n, -1), low(n, 0);
  std::vector<uint8_t> onStack(n, 0);
  std::vector<int32_t> stack;
  int32_t counter = 0, sccCount = 0;
  std::function<void(int32_t)> visit = [&](int32_t v) {
    index[v] = low[v] = counter++;
    stack.push_back(v);
    onStack[v] = 1;
    for (const Link& l : g.components[v].links) {
      int32_t w = l.target;
      if (index[w] < 0) {
        visit(w);
        low[v] = std::min(low[v], low[w]);
      } else if (onStack[w]) {
        low[v] = std::min(low[v], index[w]);
      }
    }
    if (low[v] == index[v]) {
      std::vector<int32_t> members;
      int32_t w;
      do {
        w = stack.back();
        stack.pop_back();
        onStack[w] = 0;
        g.components[w].scc = sccCount;
        members.push_back(w);
      } while (w != v);
      bool selfLoop = false;
      for (const Link& l : g.components[v].links) selfLoop = selfLoop || l.target == v;
      if (members.size() > 1 || selfLoop)
        for (int32_t m : members) g.components[m].recursive = true;
      ++sccCount;
    }
  };
  for (size_t v = 0; v < n; ++v)
    if (index[v] < 0) visit(int32_t(v));
}

// Every cycle needs a component with a recursion depth, or the expansion would not end:
// the links between components without one must form no cycle.
void checkCycles(const Graph& g) {
  size_t n = g.components.size();
  std::vector<uint8_t> state(n, 0);  // 0 new, 1 on the path, 2 done
  std::vector<int32_t> path;
  std::function<void(int32_t)> visit = [&](int32_t v) {
    state[v] = 1;
    path.push_back(v);
    for (const Link& l : g.components[v].links) {
      int32_t w = l.target;
      if (g.components[w].depth > 0) continue;
      if (state[w] == 1) {
        std::string cycle;
        auto start = std::find(path.begin(), path.end(), w);
        for (auto it = start; it != path.end(); ++it) cycle += g.components[*it].name + " → ";
        cycle += g.components[w].name;
        const Location& where = g.table.location(l.location);
        throw Error(where.source, where.pointer,
                    fmt::format("the cycle {} has no recursion depth: give one of its components a \"depth\"", cycle));
      }
      if (state[w] == 0) visit(w);
    }
    path.pop_back();
    state[v] = 2;
  };
  for (size_t v = 0; v < n; ++v)
    if (g.components[v].depth == 0 && state[v] == 0) visit(int32_t(v));
}

}  // namespace

std::shared_ptr<const Graph> parseGraph(const Json& json, const std::string& source,
                                        const std::filesystem::path& baseDir, const std::vector<Override>& overrides) {
  auto g = std::make_shared<Graph>();
  g->source = source;
  g->baseDir = baseDir;
  JsonObject root(json, source);
  if (!root.has("tendril_graph"))
    throw root.error("tendril_graph", fmt::format("is required: the graph format version (this build reads {})",
                                                  kGraphFormatVersion));
  int64_t version = root.integer("tendril_graph", 0, 0, 1000000);
  if (version != kGraphFormatVersion)
    throw root.error("tendril_graph", fmt::format("graph format version {} is not supported (this build reads {})",
                                                  version, kGraphFormatVersion));
  g->name = root.string("name", std::filesystem::path(source).stem().string());
  g->seed = root.seed("seed", 1);
  g->maxInstances = size_t(root.integer("max_instances", int64_t(g->maxInstances), 1, int64_t(1) << 32));

  // Overrides by key; each is consumed when its parameter is read.
  std::map<std::string, const Override*> pending;
  for (const Override& o : overrides) {
    if (o.key.find('/') == std::string::npos)
      throw Error(o.location.source, o.location.pointer,
                  fmt::format("override \"{}\" must name \"component/parameter\"", o.key));
    pending[o.key] = &o;
  }

  std::vector<JsonObject> comps = root.objectArray("components");
  std::map<std::string, int32_t> names;
  for (size_t i = 0; i < comps.size(); ++i) {
    if (!comps[i].has("name")) throw comps[i].error("name", "is required (a unique component name)");
    std::string name = comps[i].string("name", "");
    if (name.empty() || name.find('/') != std::string::npos)
      throw comps[i].error("name", "must be a non-empty name without '/'");
    if (!names.emplace(name, int32_t(i)).second)
      throw comps[i].error("name", fmt::format("component name \"{}\" is used twice", name));
  }
  g->components.resize(comps.size());
  for (size_t i = 0; i < comps.size(); ++i) {
    JsonObject& o = comps[i];
    Component& c = g->components[i];
    c.name = o.string("name", "");
    c.location = g->table.addLocation(source, o.pointer());
    c.type = readType(o);
    c.depth = int(o.integer("depth", 0, 1, 1000));
    c.exclude = readFlags(o, "exclude");
    c.only = readFlags(o, "only");
    c.links = readLinks(o, names, g->table);
    static const Json kEmpty = Json::object();
    const Json* pj = o.find("params");
    JsonObject params(pj ? *pj : kEmpty, source, o.pointerTo("params"));
    ParamReader r(params, g->table, c.name, pending);
    c.basic = readBasic(r, baseDir);
    switch (c.type) {
      case ComponentType::Simple: c.params = readSimple(r); break;
      case ComponentType::Revo: c.params = readRevo(r); break;
      case ComponentType::Horn: c.params = readHorn(r); break;
      case ComponentType::Leaf: c.params = readLeaf(r); break;
      case ComponentType::Tree: c.params = readTree(r); break;
      case ComponentType::Hydra: c.params = readHydra(r); break;
      case ComponentType::Wreath: c.params = readWreath(r); break;
      case ComponentType::Phiball: c.params = readPhiball(r); break;
      case ComponentType::Ffd: c.params = readFfd(r); break;
      case ComponentType::Hyperpatch: c.params = readHyperpatch(r, g->table); break;
      case ComponentType::World: c.params = readWorld(r); break;
    }
    params.finish();
    o.finish();
  }

  static const Json kNoRoot = Json::object();
  JsonObject rootComponent = root.has("root") ? root.object("root") : JsonObject(kNoRoot, source, "/root");
  if (auto cam = rootComponent.optionalObject("camera")) {
    g->camera.eye = cam->vec3("eye", g->camera.eye, -1e6, 1e6);
    g->camera.target = cam->vec3("target", g->camera.target, -1e6, 1e6);
    g->camera.fov = cam->numberf("fov", g->camera.fov, 1.0, 179.0);
    if ((g->camera.eye - g->camera.target).norm() < 1e-6f)
      throw cam->error("eye", "the eye and the target are the same point");
    g->camera.given = true;
    cam->finish();
  }
  for (JsonObject& l : rootComponent.objectArray("lights")) {
    GraphLight light;
    light.direction = l.direction("direction", light.direction);
    light.intensity = l.numberf("intensity", 1.0f, 0.0, 1e6);
    l.finish();
    g->lights.push_back(light);
  }
  if (g->lights.empty()) g->lights.push_back(GraphLight());
  if (auto bark = rootComponent.optionalObject("bark")) {
    Location where{source, bark->pointerTo("texture")};
    g->bark.texture = resolveTexture(bark->string("texture", g->bark.texture), where, baseDir);
    g->bark.color = bark->vec3("color", g->bark.color, 0.0, 1.0);
    g->bark.roughness = bark->numberf("roughness", g->bark.roughness, 0.0, 1.0);
    bark->finish();
  }
  g->rootLinks = readLinks(rootComponent, names, g->table);
  for (const Link& l : g->rootLinks)
    if (l.type != LinkType::Child) {
      const Location& where = g->table.location(l.location);
      throw Error(where.source, where.pointer, "links of the root are child links");
    }
  rootComponent.finish();
  root.finish();

  for (const auto& [key, o] : pending) {
    std::string component = key.substr(0, key.find('/'));
    std::string param = key.substr(key.find('/') + 1);
    int32_t c = g->find(component);
    if (c < 0)
      throw Error(o->location.source, o->location.pointer,
                  fmt::format("override \"{}\": the graph has no component named \"{}\"", key, component));
    throw Error(o->location.source, o->location.pointer,
                fmt::format("override \"{}\": a {} component has no parameter \"{}\"", key,
                            componentTypeName(g->components[size_t(c)].type), param));
  }

  findRecursions(*g);
  checkCycles(*g);
  return g;
}

std::shared_ptr<const Graph> loadGraph(const std::filesystem::path& path, const std::vector<Override>& overrides) {
  if (!std::filesystem::exists(path)) throw Error(path.string(), "", "graph file does not exist");
  Json json = readJsonFile(path);
  return parseGraph(json, path.string(), path.parent_path(), overrides);
}

Override parseOverride(const std::string& text, const std::string& source, const std::string& option) {
  size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error(source, option, fmt::format("expected component/parameter=value, got \"{}\"", text));
  Override o;
  o.key = text.substr(0, eq);
  std::string value = text.substr(eq + 1);
  o.location = {source, option + " " + o.key};
  Json parsed = Json::parse(value, nullptr, false);
  o.value = parsed.is_discarded() ? Json(value) : parsed;
  return o;
}

}  // namespace tendril::graph
