#include "tendril/scene/model_types.h"
#include "tendril/scene/scene.h"

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/env/mesh_import.h"
#include "tendril/env/primitives.h"
#include "tendril/models/registry.h"
#include "tendril/scene/settings_schema.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <set>

namespace tendril::scene {

namespace {

// A mesh given in the scene itself (what the Python module and the Blender add-on write):
// "vertices" [x0, y0, z0, x1, ...] and "triangles" [i0, i1, i2, ...], flat arrays.
TriangleMesh readInlineMesh(JsonObject& o) {
  constexpr size_t kMaxVertices = size_t(1) << 24, kMaxTriangles = size_t(1) << 25;
  const Json* v = o.find("vertices");
  if (!v->is_array() || v->size() % 3 != 0 || v->empty())
    throw o.error("vertices", "expected a flat array of x, y, z coordinates (a multiple of 3 numbers, at least 3)");
  if (v->size() / 3 > kMaxVertices)
    throw o.error("vertices", fmt::format("has {} vertices, more than the {} a mesh may have", v->size() / 3, kMaxVertices));
  const std::vector<float> xyz = o.numberArray("vertices", -JsonObject::kWorldExtent, JsonObject::kWorldExtent);
  TriangleMesh mesh;
  mesh.positions.resize(xyz.size() / 3);
  for (size_t i = 0; i < mesh.positions.size(); ++i) mesh.positions[i] = Vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  const Json* t = o.find("triangles");
  if (!t) throw o.error("triangles", "is required with \"vertices\" (a flat array of vertex indices, 3 per triangle)");
  if (!t->is_array() || t->size() % 3 != 0 || t->empty())
    throw o.error("triangles", "expected a flat array of vertex indices (a multiple of 3, at least 3)");
  if (t->size() / 3 > kMaxTriangles)
    throw o.error("triangles", fmt::format("has {} triangles, more than the {} a mesh may have", t->size() / 3, kMaxTriangles));
  mesh.indices.resize(t->size());
  for (size_t i = 0; i < t->size(); ++i) {
    const Json& e = (*t)[i];
    if (!e.is_number_integer() || e.get<int64_t>() < 0 || uint64_t(e.get<int64_t>()) >= mesh.positions.size())
      throw Error(o.source(), o.pointerTo("triangles") + "/" + std::to_string(i),
                  fmt::format("must be a vertex index in [0, {}], got {}", mesh.positions.size() - 1, e.dump()));
    mesh.indices[i] = uint32_t(e.get<int64_t>());
  }
  return mesh;
}

env::ObstacleDef readObstacle(JsonObject& o, const std::filesystem::path& baseDir, size_t index) {
  env::ObstacleDef d;
  std::string type = o.choice("type", "", {"plane", "box", "sphere", "cylinder", "wall", "mesh"});
  if (!o.has("type")) throw o.error("type", "is required: one of plane, box, sphere, cylinder, wall, mesh");
  d.name = o.string("name", fmt::format("{}{}", type, index));
  d.source = o.source();
  d.worldFromLocal = readTransform(o, true);
  d.color = o.vec3("color", d.color, 0.0, 1.0);
  d.sdfCell = o.numberf("sdf_cell", 0.0f, 0.0, 10.0);
  if (type == "plane") {
    d.kind = env::ObstacleKind::Plane;
    d.mesh = env::makePlane(o.vec2("size", Vec2(20, 20), 1e-3, 1e5), o.numberf("thickness", 0.2f, 1e-3, 100.0));
  } else if (type == "box") {
    d.kind = env::ObstacleKind::Box;
    d.mesh = env::makeBox(o.vec3("size", Vec3(1, 1, 1), 1e-4, 1e5));
  } else if (type == "sphere") {
    d.kind = env::ObstacleKind::Sphere;
    d.mesh = env::makeSphere(o.numberf("radius", 0.5f, 1e-4, 1e5), int(o.integer("subdivisions", 4, 0, 7)));
  } else if (type == "cylinder") {
    d.kind = env::ObstacleKind::Cylinder;
    d.mesh = env::makeCylinder(o.numberf("radius", 0.5f, 1e-4, 1e5), o.numberf("height", 1.0f, 1e-4, 1e5),
                               int(o.integer("segments", 48, 3, 4096)));
  } else if (type == "wall") {
    d.kind = env::ObstacleKind::Wall;
    Vec3 size = o.vec3("size", Vec3(4, 3, 0.25f), 1e-4, 1e5);
    std::vector<env::WallOpening> openings;
    for (JsonObject& w : o.objectArray("openings")) {
      env::WallOpening op;
      if (!w.has("center")) throw w.error("center", "is required ([x, y] on the wall, m)");
      if (!w.has("size")) throw w.error("size", "is required ([width, height], m)");
      op.center = w.vec2("center", Vec2::Zero());
      op.size = w.vec2("size", Vec2::Zero(), 1e-4, 1e5);
      w.finish();
      openings.push_back(op);
    }
    std::string bad = env::checkWallOpenings(size, openings);
    if (!bad.empty()) throw o.error("openings", bad);
    d.mesh = env::makeWall(size, openings);
  } else {
    d.kind = env::ObstacleKind::Mesh;
    if (o.has("path") == o.has("vertices"))
      throw o.error(o.has("path") ? "vertices" : "path",
                    o.has("path") ? "and \"path\" cannot both be given: a mesh comes from a file or from arrays"
                                  : "is required for a mesh obstacle (a mesh file Assimp reads), or \"vertices\" "
                                    "and \"triangles\"");
    if (o.has("vertices")) {
      d.mesh = readInlineMesh(o);
    } else {
      std::filesystem::path p = o.string("path", "");
      if (p.is_relative()) p = baseDir / p;
      d.source = p.lexically_normal().string();
      d.mesh = env::loadMeshFile(p.lexically_normal());
    }
    // Scale is baked into the mesh; the obstacle keeps a rigid transform (DESIGN: SDFs move
    // with the obstacle's rigid transform).
    Vec3 scale = Vec3::Ones();
    if (const Json* s = o.find("scale")) {
      if (s->is_number()) scale = Vec3::Constant(o.numberf("scale", 1.0f, 1e-6, 1e6));
      else scale = o.vec3("scale", Vec3::Ones(), 1e-6, 1e6);
    }
    for (Vec3& v : d.mesh.positions) v = v.cwiseProduct(scale);
  }
  o.finish();
  return d;
}

wind::SphSettings readSph(JsonObject& o, bool* fill) {
  wind::SphSettings s;
  s.domainMin = o.requiredVec3("domain_min");
  s.domainMax = o.requiredVec3("domain_max");
  if (!(s.domainMax.array() > s.domainMin.array()).all())
    throw o.error("domain_max", "must be greater than domain_min in every coordinate");
  s.spacing = o.numberf("spacing", s.spacing, 0.005, 10.0);
  s.restDensity = o.numberf("rest_density", s.restDensity, 1.2, 1.4);
  s.viscosity = o.numberf("viscosity", s.viscosity, 0.0, 10.0);
  s.soundSpeed = o.numberf("sound_speed", s.soundSpeed, 0.1, 1000.0);
  s.solver = o.choice("solver", "weakly-compressible", {"weakly-compressible", "position-based"}) == "position-based"
                 ? wind::SphSolver::PositionBased
                 : wind::SphSolver::WeaklyCompressible;
  s.iterations = int(o.integer("iterations", s.iterations, 1, 50));
  s.kernel = o.choice("kernel", "anisotropic", {"anisotropic", "isotropic"}) == "isotropic" ? wind::SphKernel::Isotropic
                                                                                             : wind::SphKernel::Anisotropic;
  // "boundary": one kind for every face, or an object naming faces ("-x" … "+z"; the others
  // outflow).
  auto kind = [](const std::string& k) { return k == "closed" ? wind::SphBoundary::Closed : wind::SphBoundary::Outflow; };
  if (const Json* b = o.has("boundary") ? &o.json().at("boundary") : nullptr; b && b->is_object()) {
    JsonObject faces = o.object("boundary");
    static const char* kFaces[6] = {"-x", "+x", "-y", "+y", "-z", "+z"};
    for (int f = 0; f < 6; ++f) s.faces[size_t(f)] = kind(faces.choice(kFaces[f], "outflow", {"outflow", "closed"}));
    faces.finish();
  } else {
    s.setBoundary(kind(o.choice("boundary", "outflow", {"outflow", "closed"})));
  }
  s.maxParticles = size_t(o.integer("max_particles", int64_t(s.maxParticles), 1, 100'000'000));
  *fill = o.boolean("fill", true);
  o.finish();
  return s;
}

models::PlantSpec readPlant(JsonObject& o, const std::filesystem::path& baseDir, size_t index) {
  models::PlantSpec p;
  p.pointer = o.pointer();
  p.name = o.string("name", fmt::format("plant{}", index));
  p.model = o.string("model", "climb");
  const models::ModelType* model = scene::findModelType(p.model);
  if (!model) {
    std::string names;
    for (const models::ModelType& t : scene::modelTypes()) names += (names.empty() ? "\"" : ", \"") + t.name + "\"";
    throw o.error("model", fmt::format("must be one of {}, got \"{}\"", names, p.model));
  }
  if (!o.has("position")) throw o.error("position", "is required (the seed point, [x, y, z] in m)");
  p.position = o.vec3("position", Vec3::Zero());
  p.direction = o.direction("direction", Vec3::UnitY());
  p.seed = o.seed("seed", index + 1);
  p.support = o.boolean("support", false);
  p.params = model->read(o, baseDir);
  o.finish();
  return p;
}

}  // namespace

Scene parseScene(const Json& json, const std::string& source, const std::filesystem::path& baseDir) {
  JsonObject root(json, source);
  Scene scene;
  scene.source = source;
  if (!root.has("tendril"))
    throw root.error("tendril", fmt::format("is required: the scene format version (this build reads {})",
                                            kSceneFormatVersion));
  int64_t version = root.integer("tendril", 0, 0, 1000000);
  if (version != kSceneFormatVersion)
    throw root.error("tendril", fmt::format("scene format version {} is not supported (this build reads {})",
                                            version, kSceneFormatVersion));
  scene.description = root.string("description", "");
  scene.seed = root.seed("seed", 1);
  scene.steps = int(root.integer("steps", scene.steps, 0, 10000000));
  scene.stepTime = root.numberf("step_time", scene.stepTime, 1e-6, 1e9);

  if (auto e = root.optionalObject("environment")) {
    std::vector<JsonObject> obstacles = e->objectArray("obstacles");
    std::set<std::string> names;
    for (size_t i = 0; i < obstacles.size(); ++i) {
      scene.obstacles.push_back(readObstacle(obstacles[i], baseDir, i));
      if (!names.insert(scene.obstacles.back().name).second)
        throw Error(source, obstacles[i].pointerTo("name"),
                    fmt::format("obstacle name \"{}\" is used twice", scene.obstacles.back().name));
    }
    for (JsonObject& l : e->objectArray("lights")) {
      scene.lights.push_back(normalised(readLight(l)));
      l.finish();
    }
    for (JsonObject& s : e->objectArray("strokes")) {
      scene.strokes.push_back(readStroke(s));
      s.finish();
    }
    if (auto w = e->optionalObject("wind")) {
      scene.wind = readWind(*w);
      for (env::WindEmitter& em : scene.wind.emitters) em = normalised(em);
      if (auto sph = w->optionalObject("sph")) {
        if (scene.wind.mode != env::WindMode::Sph) throw w->error("sph", "only applies with \"mode\": \"sph\"");
        scene.sph = readSph(*sph, &scene.sphFill);
      } else if (scene.wind.mode == env::WindMode::Sph) {
        throw w->error("sph", "is required with \"mode\": \"sph\" (the simulated box: domain_min, domain_max)");
      }
      w->finish();
    }
    e->finish();
  }
  std::vector<JsonObject> plants = root.objectArray("plants");
  std::set<std::string> plantNames;
  for (size_t i = 0; i < plants.size(); ++i) {
    scene.plants.push_back(readPlant(plants[i], baseDir, i));
    if (!plantNames.insert(scene.plants.back().name).second)
      throw Error(source, plants[i].pointerTo("name"),
                  fmt::format("plant name \"{}\" is used twice", scene.plants.back().name));
  }
  if (auto o = root.optionalObject("output")) scene.output = readOutput(*o);
  root.finish();
  return scene;
}

models::PlantSpec parsePlant(const Json& plant, const std::string& source, const std::string& pointer,
                     const std::filesystem::path& baseDir, size_t index) {
  if (!plant.is_object()) throw Error(source, pointer, "expected a plant object, got " + describeJson(plant));
  JsonObject o(plant, source, pointer);
  return readPlant(o, baseDir, index);
}

Scene loadScene(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw Error(path.string(), "", "scene file does not exist");
  Json json = readJsonFile(path);
  Scene scene = parseScene(json, path.string(), path.parent_path());
  scene.path = path;
  return scene;
}

void populateEnvironment(const Scene& scene, env::Environment& env) {
  for (const env::ObstacleDef& o : scene.obstacles) env.addObstacle(o);
  for (const env::Light& l : scene.lights) env.addLight(l);
  for (const env::Stroke& s : scene.strokes) env.addStroke(s);
  env.setWind(scene.wind);
  env.commit();
}

}  // namespace tendril::scene
