#include "tendril/scene/model_types.h"
#include "tendril/session/edit.h"

#include "tendril/core/error.h"
#include "tendril/models/registry.h"
#include "tendril/scene/settings_schema.h"
#include "tendril/session/session.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>

namespace tendril::session {

namespace {

// --- JSON ---

Json vec3Json(const Vec3& v) { return Json::array({v.x(), v.y(), v.z()}); }

// A direction as written, not normalised: the edit normalises it when applied, so that an edit
// read back from its own JSON is the same value (journals replay bit for bit).
Vec3 readDirection(JsonObject& o, std::string_view key, const Vec3& fallback) {
  const Vec3 v = o.vec3(key, fallback);
  if (v.squaredNorm() == 0.0f) throw o.error(key, "must not be the zero vector");
  return v;
}

uint32_t readIndex(JsonObject& o, std::string_view key) {
  if (!o.has(key)) throw o.error(key, "is required (an index, counting from 0)");
  return uint32_t(o.integer(key, 0, 0, std::numeric_limits<uint32_t>::max() - 1));
}

// "scale": a number (uniform) or [x, y, z]; each factor in [1e-4, 1e4].
Vec3 readScale(JsonObject& o, std::string_view key) {
  const Json* s = o.find(key);
  if (s && s->is_number()) return Vec3::Constant(o.numberf(key, 1.0f, 1e-4, 1e4));
  if (s && !s->is_array()) throw o.error(key, "expected a number or [x, y, z] (factors > 0), got " + describeJson(*s));
  return o.vec3(key, Vec3::Ones(), 1e-4, 1e4);
}

// A uniform scale is written as one number.
Json scaleJson(const Vec3& s) {
  if (s.x() == s.y() && s.y() == s.z()) return s.x();
  return vec3Json(s);
}

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

// --- applying ---

void requirePlant(const Session& s, uint32_t plant, const char* what) {
  if (plant >= s.plantCount())
    throw Error(what, "/plant", fmt::format("there is no plant {} (the session has {})", plant, s.plantCount()));
}

// The plant's system's capability `C` (e.g. &models::PlantSystem::grip); Error naming the
// edit when the plant's model does not have it.
template <class C>
C& capability(Session& s, uint32_t plant, C* (models::PlantSystem::*get)(), const char* what) {
  requirePlant(s, plant, what);
  C* c = (s.system(plant).*get)();
  if (!c)
    throw Error(what, "/plant",
                fmt::format("plant {} is of model \"{}\", which cannot do this", plant, s.plantSpec(plant).model));
  return *c;
}

void requireFinite(const Vec3& v, const char* what, const char* key) {
  if (!isFinite(v)) throw Error(what, std::string("/") + key, "is not finite");
}

// A transform an edit can apply: finite, with a normalised rotation.
RigidTransform checkedTransform(RigidTransform t, const char* what) {
  requireFinite(t.translation, what, "position");
  const float n = t.rotation.norm();
  if (!(n > 1e-6f) || !std::isfinite(n)) throw Error(what, "/rotation", "is not a rotation");
  t.rotation.normalize();
  return t;
}

// A settings check's "/key: message" (scene/settings_schema.h) as the edit's Error.
Error settingsError(const char* what, const std::string& bad) {
  const size_t colon = bad.find(": ");
  return Error(what, bad.substr(0, colon), bad.substr(colon + 2));
}

// A value an edit can apply: within the limits the readers apply, its direction normalised.
env::WindEmitter checkedEmitter(const env::WindEmitter& e, const char* what) {
  if (auto bad = scene::checkEmitter(e)) throw settingsError(what, *bad);
  return scene::normalised(e);
}

// The scene-plant key of the model's settings ("species", "grammar", "graph").
std::string plantKeyFor(const std::string& model) {
  const models::ModelType* type = scene::findModelType(model);
  return type ? type->settingsKey : "species";
}

// Applies one edit to the session: std::visit over the Edit's alternatives, one function each.
struct EditApplier {
  Session& s;
  Editor& editor;
  Editor::Drag& drag;
  env::Environment& env;
  void operator()(const SeedPlant& e) const;
  void operator()(const SeedBranch& e) const;
  void operator()(const Cut& e) const;
  void operator()(const DragBegin& e) const;
  void operator()(const DragMove& e) const;
  void operator()(const DragEnd&) const;
  void operator()(const PaintStroke& e) const;
  void operator()(const MoveObstacle& e) const;
  void operator()(const AddObstacle& e) const;
  void operator()(const MoveLight& e) const;
  void operator()(const AddEmitter& e) const;
  void operator()(const EditEmitter& e) const;
  void operator()(const RemoveEmitter& e) const;
  void operator()(const SetSpecies& e) const;
  void operator()(const SetGrammar& e) const;
  void operator()(const SetGraph& e) const;
  void operator()(const Step& e) const;
  void operator()(const Undo&) const;
  void operator()(const Redo&) const;
};

void EditApplier::operator()(const SeedPlant& e) const {
  requireFinite(e.position, "seed_plant", "position");
  requireFinite(e.normal, "seed_plant", "normal");
  if (e.normal.squaredNorm() == 0.0f) throw Error("seed_plant", "/normal", "must not be zero");
  Json plant = Json::object();
  std::string name = e.name;
  for (size_t n = s.plantCount(); name.empty(); ++n) {
    std::string candidate = fmt::format("plant{}", n);
    bool used = false;
    for (size_t i = 0; i < s.plantCount(); ++i) used |= s.plantSpec(i).name == candidate;
    if (!used) name = candidate;
  }
  plant["name"] = name;
  plant["model"] = e.model;
  plant["position"] = vec3Json(e.position);
  plant["direction"] = vec3Json(e.normal);
  plant["seed"] = e.seed;
  if (!e.species.empty()) plant[plantKeyFor(e.model)] = e.species;
  s.addPlant(plant, "seed_plant");
}

void EditApplier::operator()(const SeedBranch& e) const {
  models::BranchSeeding& b = capability(s, e.plant, &models::PlantSystem::branchSeeding, "seed_branch");
  requireFinite(e.direction, "seed_branch", "direction");
  b.seedBranch(s.indexInSystem(e.plant), e.particle, e.direction, "seed_branch");
}

void EditApplier::operator()(const Cut& edit) const {
  requirePlant(s, edit.plant, "cut");
  if (edit.inside) {
    // One branch at a time, found again after each cut (a cut may renumber the nodes): the
    // first node inside the box on a path from the root, of what is still part of the plant.
    size_t lastNode = SIZE_MAX, lastCount = SIZE_MAX;
    for (size_t guard = 0; guard < 100000; ++guard) {
      const plant::PlantModel p = std::as_const(s).system(edit.plant).snapshot(s.indexInSystem(edit.plant));
      // A segment is inside if its start, middle or tip is.
      auto in = [&](size_t i) {
        if (p.flags[i] & plant::kNodeBroken) return false;
        const Vec3 a = p.position[i], b = p.tip(i);
        return edit.inside->contains(a) || edit.inside->contains(0.5f * (a + b)) || edit.inside->contains(b);
      };
      size_t node = p.nodeCount();
      for (size_t i = 0; i < p.nodeCount() && node == p.nodeCount(); ++i)
        if (p.parent[i] >= 0 && in(i) && !in(size_t(p.parent[i]))) node = i;
      if (node == p.nodeCount() || (node == lastNode && p.nodeCount() == lastCount)) break;  // done, or stuck
      lastNode = node, lastCount = p.nodeCount();
      Cut one;
      one.plant = edit.plant;
      one.node = uint32_t(node);
      one.remove = edit.remove;
      (*this)(one);
    }
    return;
  }
  Cut e = edit;
  if (e.particle != Cut::kByNode) {
    const models::Grip& g = capability(s, e.plant, &models::PlantSystem::grip, "cut");
    g.requireHandle(s.indexInSystem(e.plant), e.particle, "cut");
    const std::vector<uint32_t> handles = g.nodeHandles(s.indexInSystem(e.plant));
    const auto at = std::find(handles.begin(), handles.end(), e.particle);
    if (at == handles.end())
      throw Error("cut", "/particle", fmt::format("plant {}: particle {} is not a segment of the plant", e.plant,
                                                  e.particle));
    e.node = uint32_t(at - handles.begin());
  }
  // A support plant's cut branch takes what clings to it: found before the cut, while the
  // environment still holds the branch's stems.
  std::vector<bool> removed;
  if (s.plantSpec(e.plant).support) {
    const plant::PlantModel host = std::as_const(s).system(e.plant).snapshot(s.indexInSystem(e.plant));
    if (e.node < host.nodeCount()) {
      removed.assign(host.nodeCount(), false);
      removed[e.node] = true;
      for (size_t i = e.node + 1; i < host.nodeCount(); ++i)
        removed[i] = host.parent[i] >= 0 && removed[size_t(host.parent[i])];
    }
  }
  try {
    s.system(e.plant).cut(s.indexInSystem(e.plant), e.node, e.remove);
  } catch (const Error& err) {
    throw Error("cut", "/node", fmt::format("plant {} (model \"{}\"): {}", e.plant, s.plantSpec(e.plant).model,
                                            err.message()));
  }
  if (removed.empty()) return;
  // One climber branch at a time, the last first: a cut may renumber the plant's nodes.
  for (size_t guard = 0; guard < 100000; ++guard) {
    const auto held = s.clingingTo(e.plant, removed);
    if (held.empty()) break;
    const auto [plant, node] = held.back();
    const size_t before = std::as_const(s).system(plant).segmentCount();
    s.system(plant).cut(s.indexInSystem(plant), node, e.remove);
    if (std::as_const(s).system(plant).segmentCount() == before) break;  // nothing came off: stop
  }
}

void EditApplier::operator()(const DragBegin& e) const {
  if (editor.dragging()) throw Error("drag_begin", "", "a drag is already under way (end it with drag_end)");
  models::Grip& g = capability(s, e.plant, &models::PlantSystem::grip, "drag_begin");
  g.requireHandle(s.indexInSystem(e.plant), e.particle, "drag_begin");
  requireFinite(e.target, "drag_begin", "target");
  if (!(e.strength >= 0.0f && e.strength <= 1.0f))
    throw Error("drag_begin", "/strength", fmt::format("must be in [0, 1], got {}", e.strength));
  g.setDrag(e.particle, e.target, e.strength);
  drag.plant = e.plant, drag.handle = e.particle, drag.strength = e.strength;
}

void EditApplier::operator()(const DragMove& e) const {
  if (!editor.dragging()) throw Error("drag_move", "", "no drag is under way (start one with drag_begin)");
  requireFinite(e.target, "drag_move", "target");
  // The grip is lost when the dragged part broke off and went.
  if (drag.plant < s.plantCount())
    if (models::Grip* g = s.system(drag.plant).grip()) g->setDrag(drag.handle, e.target, drag.strength);
}

void EditApplier::operator()(const DragEnd&) const {
  if (!editor.dragging()) throw Error("drag_end", "", "no drag is under way");
  if (drag.plant < s.plantCount())
    if (models::Grip* g = s.system(drag.plant).grip()) g->clearDrag();
}

void EditApplier::operator()(const PaintStroke& e) const {
  const env::Stroke& st = e.stroke;
  if (auto bad = scene::checkStroke(st)) throw settingsError("paint_stroke", *bad);
  env.addStroke(st);
  s.environmentChanged();
  // An attracting stroke near a full-grown branch seeds a branch there, toward the
  // stroke (seed 000 §5.1), in every model that can.
  for (models::PlantSystem* system : s.systems())
    if (models::BranchSeeding* b = system->branchSeeding()) b->seedBranchNear(st);
}

void EditApplier::operator()(const MoveObstacle& e) const {
  if (e.obstacle >= env.obstacleCount())
    throw Error("move_obstacle", "/obstacle",
                fmt::format("there is no obstacle {} (the scene has {})", e.obstacle, env.obstacleCount()));
  const RigidTransform t = checkedTransform(e.worldFromLocal, "move_obstacle");
  // What holds on to the obstacle moves with it (seed 000 Fig. 9), asked of the environment
  // as it stands before the move.
  const RigidTransform motion = t * env.obstacle(e.obstacle).worldFromLocal.inverse();
  for (models::PlantSystem* system : s.systems())
    if (models::ObstacleHold* hold = system->obstacleHold()) hold->obstacleMoving(env, e.obstacle, motion);
  if (e.scale) {
    try {
      s.setObstacleScale(e.obstacle, *e.scale);  // may replace the environment
    } catch (const Error& err) {
      throw Error("move_obstacle", err.location(), err.message());
    }
  }
  s.environment().setObstacleTransform(e.obstacle, t);
  s.environmentChanged();
}

void EditApplier::operator()(const AddObstacle& e) const {
  const RigidTransform t = checkedTransform(e.worldFromLocal, "add_obstacle");
  if (!isFinite(e.color) || !(e.color.array() >= 0.0f).all() || !(e.color.array() <= 1.0f).all())
    throw Error("add_obstacle", "/color", "must be linear RGB in [0, 1]");
  try {
    s.importObstacle(e.path, e.name, t, e.scale, e.color);
  } catch (const Error& err) {
    if (!err.source().empty()) throw;  // the mesh file's own error names it
    throw Error("add_obstacle", err.location(), err.message());
  }
}

void EditApplier::operator()(const MoveLight& e) const {
  std::vector<env::Light> lights = env.lights();
  if (e.light >= lights.size())
    throw Error("move_light", "/light",
                fmt::format("there is no light {} (the scene has {})", e.light, lights.size()));
  if (auto bad = scene::checkLight(e.value)) throw settingsError("move_light", *bad);
  lights[e.light] = scene::normalised(e.value);
  env.setLights(std::move(lights));
}

void requireEmitter(const std::vector<env::WindEmitter>& list, uint32_t index, const char* what) {
  if (index >= list.size())
    throw Error(what, "/index", fmt::format("there is no emitter {} (the scene has {})", index, list.size()));
}

void EditApplier::operator()(const AddEmitter& e) const {
  std::vector<env::WindEmitter> list = env.windField().settings().emitters;
  list.push_back(checkedEmitter(e.emitter, "add_emitter"));
  s.setEmitters(std::move(list));
}

void EditApplier::operator()(const EditEmitter& e) const {
  std::vector<env::WindEmitter> list = env.windField().settings().emitters;
  requireEmitter(list, e.index, "edit_emitter");
  list[e.index] = checkedEmitter(e.emitter, "edit_emitter");
  s.setEmitters(std::move(list));
}

void EditApplier::operator()(const RemoveEmitter& e) const {
  std::vector<env::WindEmitter> list = env.windField().settings().emitters;
  requireEmitter(list, e.index, "remove_emitter");
  list.erase(list.begin() + e.index);
  s.setEmitters(std::move(list));
}

void EditApplier::operator()(const SetSpecies& e) const {
  requirePlant(s, e.plant, "set_species");
  if (!e.keys.is_object())
    throw Error("set_species", "/species", "expected an object of species keys, got " + describeJson(e.keys));
  Json plant = s.plantDescription(e.plant);
  if (!plant.is_object())
    throw Error("set_species", "/plant", fmt::format("plant {} was added from code; its species cannot be edited", e.plant));
  Json species = plant.contains("species") ? plant["species"] : Json::object();
  if (species.is_string()) species = Json{{"base", species.get<std::string>()}};
  for (auto it = e.keys.begin(); it != e.keys.end(); ++it) species[it.key()] = it.value();
  plant["species"] = species;
  s.setPlantDescription(e.plant, plant, "set_species");
}

void EditApplier::operator()(const SetGrammar& e) const {
  requirePlant(s, e.plant, "set_grammar");
  if (s.plantSpec(e.plant).model != "lsystem")
    throw Error("set_grammar", "/plant",
                fmt::format("plant {} is of model \"{}\"; only L-system plants have a grammar", e.plant,
                            s.plantSpec(e.plant).model));
  Json plant = s.plantDescription(e.plant);
  if (!plant.is_object())
    throw Error("set_grammar", "/plant", fmt::format("plant {} was added from code; its grammar cannot be edited", e.plant));
  plant["grammar_text"] = e.text;
  if (e.derivationLength) plant["derivation_length"] = *e.derivationLength;
  try {
    s.setPlantDescription(e.plant, plant, "set_grammar");
  } catch (const Error& err) {
    // Errors in the text are placed in it (line:col), as the CLI prints them.
    const std::string& loc = err.location();
    const bool inText = !loc.empty() && std::isdigit(static_cast<unsigned char>(loc[0]));
    throw Error("set_grammar", inText ? "/text " + loc : "/text", err.message());
  }
}

void EditApplier::operator()(const SetGraph& e) const {
  requirePlant(s, e.plant, "set_graph");
  if (s.plantSpec(e.plant).model != "graph")
    throw Error("set_graph", "/plant",
                fmt::format("plant {} is of model \"{}\"; only graph plants have a p-graph", e.plant,
                            s.plantSpec(e.plant).model));
  if (!e.graph.is_object())
    throw Error("set_graph", "/graph", "expected a graph object, got " + describeJson(e.graph));
  Json plant = s.plantDescription(e.plant);
  if (!plant.is_object())
    throw Error("set_graph", "/plant", fmt::format("plant {} was added from code; its graph cannot be edited", e.plant));
  plant["graph_document"] = e.graph;
  try {
    s.setPlantDescription(e.plant, plant, "set_graph");
  } catch (const Error& err) {
    // Errors in the graph are placed in it (its own JSON pointer).
    const std::string& loc = err.location();
    const bool inGraph = !loc.empty() && loc[0] == '/' && loc.rfind("/graph", 0) != 0;
    throw Error("set_graph", inGraph ? "/graph" + loc : "/graph", err.message());
  }
}

void EditApplier::operator()(const Step& e) const {
  for (uint32_t i = 0; i < e.count; ++i) s.step();
}

void EditApplier::operator()(const Undo&) const {
  editor.undo();
}

void EditApplier::operator()(const Redo&) const {
  editor.redo();
}

void applyTo(Session& s, const Edit& edit, Editor& editor, Editor::Drag& drag) {
  std::visit(EditApplier{s, editor, drag, s.environment()}, edit);
  // A cut host, an undone edit: what climbers cling to is the plants as they now are.
  s.refreshSupports();
}

}  // namespace

// --- names and JSON ---

const char* editName(const Edit& edit) {
  static constexpr const char* kNames[] = {"seed_plant",    "seed_branch",  "cut",         "drag_begin",
                                           "drag_move",     "drag_end",     "paint_stroke", "move_obstacle",
                                           "move_light",    "add_emitter",  "edit_emitter", "remove_emitter",
                                           "set_species",   "step",         "undo",         "redo",
                                           "add_obstacle",  "set_grammar",  "set_graph"};
  static_assert(std::size(kNames) == std::variant_size_v<Edit>);
  return kNames[edit.index()];
}

Json editToJson(const Edit& edit) {
  Json j = Json::object();
  j["edit"] = editName(edit);
  std::visit(Overloaded{
                 [&](const SeedPlant& e) {
                   j["model"] = e.model;
                   if (!e.species.empty()) j["species"] = e.species;
                   if (!e.name.empty()) j["name"] = e.name;
                   j["position"] = vec3Json(e.position);
                   j["normal"] = vec3Json(e.normal);
                   j["seed"] = e.seed;
                 },
                 [&](const SeedBranch& e) {
                   j["plant"] = e.plant, j["particle"] = e.particle, j["direction"] = vec3Json(e.direction);
                 },
                 [&](const Cut& e) {
                   j["plant"] = e.plant;
                   if (e.inside) j["inside"] = {{"min", vec3Json(e.inside->min)}, {"max", vec3Json(e.inside->max)}};
                   else if (e.particle != Cut::kByNode) j["particle"] = e.particle;
                   else j["node"] = e.node;
                   if (e.remove) j["remove"] = true;
                 },
                 [&](const DragBegin& e) {
                   j["plant"] = e.plant, j["particle"] = e.particle, j["target"] = vec3Json(e.target);
                   j["strength"] = e.strength;
                 },
                 [&](const DragMove& e) { j["target"] = vec3Json(e.target); },
                 [&](const DragEnd&) {},
                 [&](const PaintStroke& e) { j.update(scene::strokeJson(e.stroke)); },
                 [&](const MoveObstacle& e) {
                   j["obstacle"] = e.obstacle;
                   scene::writeTransform(j, e.worldFromLocal);
                   if (e.scale) j["scale"] = scaleJson(*e.scale);
                 },
                 [&](const AddObstacle& e) {
                   j["path"] = e.path;
                   if (!e.name.empty()) j["name"] = e.name;
                   scene::writeTransform(j, e.worldFromLocal);
                   j["scale"] = scaleJson(e.scale);
                   j["color"] = vec3Json(e.color);
                 },
                 [&](const MoveLight& e) {
                   j["light"] = e.light;
                   j.update(scene::lightJson(e.value));
                 },
                 [&](const AddEmitter& e) { j.update(scene::emitterJson(e.emitter)); },
                 [&](const EditEmitter& e) {
                   j["index"] = e.index;
                   j.update(scene::emitterJson(e.emitter));
                 },
                 [&](const RemoveEmitter& e) { j["index"] = e.index; },
                 [&](const SetSpecies& e) { j["plant"] = e.plant, j["species"] = e.keys; },
                 [&](const SetGrammar& e) {
                   j["plant"] = e.plant, j["text"] = e.text;
                   if (e.derivationLength) j["derivation_length"] = *e.derivationLength;
                 },
                 [&](const SetGraph& e) { j["plant"] = e.plant, j["graph"] = e.graph; },
                 [&](const Step& e) { j["count"] = e.count; },
                 [&](const Undo&) {},
                 [&](const Redo&) {},
             },
             edit);
  return j;
}

Edit readEdit(JsonObject& o) {
  if (!o.has("edit")) throw o.error("edit", "is required: the kind of edit (e.g. \"seed_plant\")");
  const std::string kind = o.choice("edit", "", {"seed_plant", "seed_branch", "cut", "drag_begin", "drag_move",
                                                 "drag_end", "paint_stroke", "move_obstacle", "move_light",
                                                 "add_emitter", "edit_emitter", "remove_emitter", "set_species",
                                                 "step", "undo", "redo", "add_obstacle", "set_grammar",
                                                 "set_graph"});
  if (kind == "seed_plant") {
    SeedPlant e;
    e.model = o.string("model", e.model);
    if (!scene::findModelType(e.model)) {
      std::string names;
      for (const models::ModelType& t : scene::modelTypes()) names += (names.empty() ? "\"" : ", \"") + t.name + "\"";
      throw o.error("model", fmt::format("must be one of {}, got \"{}\"", names, e.model));
    }
    e.species = o.string("species", "");
    e.name = o.string("name", "");
    if (!o.has("position")) throw o.error("position", "is required (the seed point, [x, y, z] in m)");
    e.position = o.vec3("position", e.position);
    e.normal = readDirection(o, "normal", e.normal);
    e.seed = o.seed("seed", e.seed);
    return e;
  }
  if (kind == "seed_branch") {
    SeedBranch e;
    e.plant = readIndex(o, "plant");
    e.particle = readIndex(o, "particle");
    e.direction = readDirection(o, "direction", e.direction);
    return e;
  }
  if (kind == "cut") {
    Cut e;
    e.plant = readIndex(o, "plant");
    e.remove = o.boolean("remove", false);
    if (o.has("inside")) {
      if (o.has("particle") || o.has("node"))
        throw o.error("inside", "a cut takes \"node\", \"particle\" or \"inside\", one of them");
      JsonObject box = o.object("inside");
      Bounds3 b;
      b.min = box.requiredVec3("min");
      b.max = box.requiredVec3("max");
      if (!(b.min.array() < b.max.array()).all()) throw box.error("max", "must be above \"min\" on every axis");
      box.finish();
      e.inside = b;
      return e;
    }
    if (!o.has("particle") && !o.has("node"))
      throw o.error("node", "is required (the segment to cut; or \"particle\": the part of a particle plant; or "
                            "\"inside\": a box)");
    if (o.has("particle") && o.has("node")) throw o.error("particle", "a cut takes \"node\" or \"particle\", not both");
    if (o.has("particle")) e.particle = readIndex(o, "particle");
    else e.node = readIndex(o, "node");
    return e;
  }
  if (kind == "drag_begin") {
    DragBegin e;
    e.plant = readIndex(o, "plant");
    e.particle = readIndex(o, "particle");
    if (!o.has("target")) throw o.error("target", "is required (where the particle is pulled, [x, y, z] in m)");
    e.target = o.vec3("target", e.target);
    e.strength = o.numberf("strength", e.strength, 0.0, 1.0);
    return e;
  }
  if (kind == "drag_move") {
    DragMove e;
    if (!o.has("target")) throw o.error("target", "is required (where the particle is pulled, [x, y, z] in m)");
    e.target = o.vec3("target", e.target);
    return e;
  }
  if (kind == "drag_end") return DragEnd{};
  if (kind == "paint_stroke") return PaintStroke{scene::readStroke(o)};
  if (kind == "move_obstacle") {
    MoveObstacle e;
    e.obstacle = readIndex(o, "obstacle");
    e.worldFromLocal = scene::readTransform(o, false);
    if (o.has("scale")) e.scale = readScale(o, "scale");
    return e;
  }
  if (kind == "add_obstacle") {
    AddObstacle e;
    if (!o.has("path")) throw o.error("path", "is required: the mesh file (.obj, .ply, .stl, .gltf, .glb...)");
    e.path = o.requiredString("path");
    e.name = o.string("name", "");
    e.worldFromLocal = scene::readTransform(o, false);
    e.scale = readScale(o, "scale");
    e.color = o.vec3("color", e.color, 0.0, 1.0);
    return e;
  }
  if (kind == "move_light") {
    MoveLight e;
    e.light = readIndex(o, "light");
    e.value = scene::readLight(o);
    return e;
  }
  if (kind == "add_emitter") return AddEmitter{scene::readEmitter(o)};
  if (kind == "edit_emitter") {
    EditEmitter e;
    e.index = readIndex(o, "index");
    e.emitter = scene::readEmitter(o);
    return e;
  }
  if (kind == "remove_emitter") return RemoveEmitter{readIndex(o, "index")};
  if (kind == "set_species") {
    SetSpecies e;
    e.plant = readIndex(o, "plant");
    const Json* sp = o.find("species");
    if (!sp || !sp->is_object()) throw o.error("species", "is required: an object of species keys");
    e.keys = *sp;
    return e;
  }
  if (kind == "set_grammar") {
    SetGrammar e;
    e.plant = readIndex(o, "plant");
    if (!o.has("text")) throw o.error("text", "is required: the grammar (docs/grammar.md) as text");
    e.text = o.requiredString("text");
    if (o.has("derivation_length")) e.derivationLength = int(o.integer("derivation_length", 0, 0, 10'000'000));
    return e;
  }
  if (kind == "set_graph") {
    SetGraph e;
    e.plant = readIndex(o, "plant");
    const Json* g = o.find("graph");
    if (!g || !g->is_object()) throw o.error("graph", "is required: a graph object (docs/graph-format.md)");
    e.graph = *g;
    return e;
  }
  if (kind == "step") return Step{uint32_t(o.integer("count", 1, 1, 10'000'000))};
  if (kind == "undo") return Undo{};
  return Redo{};
}

// --- the editor ---

struct Editor::Snapshot {
  std::vector<uint8_t> state;
  bool dragging = false;
  Drag drag;
};

Editor::Editor(Session& session, size_t historyBytes) : session_(session), historyBytesCap_(historyBytes) {}
Editor::~Editor() = default;

bool Editor::canUndo() const { return !undo_.empty(); }
bool Editor::canRedo() const { return !redo_.empty(); }
size_t Editor::undoDepth() const { return undo_.size(); }
size_t Editor::redoDepth() const { return redo_.size(); }

size_t Editor::historyBytes() const {
  size_t n = 0;
  for (const Snapshot& s : undo_) n += s.state.size();
  for (const Snapshot& s : redo_) n += s.state.size();
  return n;
}

void Editor::trim() {
  // The oldest undo steps go first, then the farthest redo steps.
  size_t total = historyBytes();
  while (total > historyBytesCap_ && !undo_.empty()) {
    total -= undo_.front().state.size();
    undo_.erase(undo_.begin());
  }
  while (total > historyBytesCap_ && !redo_.empty()) {
    total -= redo_.front().state.size();
    redo_.erase(redo_.begin());
  }
}

void Editor::setJournal(std::vector<TimedEdit> journal) {
  journal_ = std::move(journal);
  stepsRun_ = 0;
  if (!journal_.empty()) {
    const TimedEdit& last = journal_.back();
    const Step* s = std::get_if<Step>(&last.edit);
    stepsRun_ = last.atStep + (s ? s->count : 0);
  }
  // A drag gesture under way when the journal was written (a session saved mid-drag) is under
  // way here too, as in a replay of the journal: the saved state still pulls the part, so
  // drag_move and drag_end go on with it and a second drag_begin is refused. The gesture is
  // followed through the journal as apply() follows it, undo and redo restoring what the
  // entry they take back held (the journal records only edits that were applied).
  struct Gesture {
    bool dragging = false;
    Drag drag;
  };
  Gesture now;
  std::vector<Gesture> undone, redone;
  for (const TimedEdit& t : journal_) {
    const Edit& e = t.edit;
    if (std::holds_alternative<Undo>(e)) {
      if (undone.empty()) continue;
      redone.push_back(now), now = undone.back(), undone.pop_back();
    } else if (std::holds_alternative<Redo>(e)) {
      if (redone.empty()) continue;
      undone.push_back(now), now = redone.back(), redone.pop_back();
    } else if (const Step* st = std::get_if<Step>(&e)) {
      if (st->count > 0) redone.clear();
    } else if (std::holds_alternative<DragEnd>(e)) {
      now.dragging = false;
    } else if (!std::holds_alternative<DragMove>(e)) {
      undone.push_back(now), redone.clear();
      if (const DragBegin* b = std::get_if<DragBegin>(&e)) now = {true, {b->plant, b->particle, b->strength}};
    }
  }
  dragging_ = now.dragging;
  drag_ = now.dragging ? now.drag : Drag{};
}

void Editor::record(uint32_t at, const Edit& edit) {
  if (const Step* s = std::get_if<Step>(&edit)) {
    if (!journal_.empty())
      if (Step* last = std::get_if<Step>(&journal_.back().edit); last && journal_.back().atStep + last->count == at) {
        last->count += s->count;
        return;
      }
  }
  journal_.push_back({at, edit});
}

void Editor::undo() {
  if (undo_.empty()) throw Error("undo", "", "there is nothing to undo");
  Snapshot now{session_.saveState(), dragging_, drag_};
  Snapshot& before = undo_.back();
  session_.loadState(before.state, "undo history");
  dragging_ = before.dragging, drag_ = before.drag;
  undo_.pop_back();
  redo_.push_back(std::move(now));
  trim();
}

void Editor::redo() {
  if (redo_.empty()) throw Error("redo", "", "there is nothing to redo");
  Snapshot now{session_.saveState(), dragging_, drag_};
  Snapshot& after = redo_.back();
  session_.loadState(after.state, "undo history");
  dragging_ = after.dragging, drag_ = after.drag;
  redo_.pop_back();
  undo_.push_back(std::move(now));
  trim();
}

void Editor::step(uint32_t count) { apply(Step{count}); }

void Editor::apply(const Edit& edit) {
  const uint32_t at = stepsRun_;
  if (std::holds_alternative<Undo>(edit) || std::holds_alternative<Redo>(edit)) {
    applyTo(session_, edit, *this, drag_);
    record(at, edit);
    return;
  }
  if (const Step* s = std::get_if<Step>(&edit)) {
    // Steps are not undo entries of their own; they change the state a redo would restore
    // onto, so the redo steps go.
    applyTo(session_, edit, *this, drag_);
    stepsRun_ += s->count;
    if (s->count > 0) redo_.clear();
    record(at, edit);
    return;
  }
  // A drag gesture is one undo entry: the one made by drag_begin.
  const bool gesture = std::holds_alternative<DragMove>(edit) || std::holds_alternative<DragEnd>(edit);
  Snapshot before{session_.saveState(), dragging_, drag_};
  try {
    applyTo(session_, edit, *this, drag_);
  } catch (const Error&) {
    session_.loadState(before.state, "undo history");
    dragging_ = before.dragging, drag_ = before.drag;
    throw;
  }
  if (std::holds_alternative<DragBegin>(edit)) dragging_ = true;
  if (std::holds_alternative<DragEnd>(edit)) dragging_ = false;
  if (!gesture) {
    undo_.push_back(std::move(before));
    redo_.clear();
    trim();
  }
  record(at, edit);
}

// --- picking ---

namespace {

// Closest points of the ray o + t d (t >= 0, d unit) and the segment a-b: the ray parameter t,
// the segment point and their distance.
float raySegment(const Vec3& o, const Vec3& d, const Vec3& a, const Vec3& b, float* t, Vec3* onSegment) {
  const Vec3 ab = b - a, ao = a - o;
  const float len2 = ab.squaredNorm();
  float s = 0.0f;
  if (len2 > 1e-12f) {
    const float dd = d.dot(ab);
    const float denom = len2 - dd * dd;  // |d| = 1
    if (denom > 1e-12f) s = std::clamp((dd * d.dot(ao) - ao.dot(ab)) / denom, 0.0f, 1.0f);
  }
  Vec3 p = a + s * ab;
  float tt = std::max(0.0f, d.dot(p - o));
  // One refinement from the ray point back to the segment handles the clamped cases.
  if (len2 > 1e-12f) {
    s = std::clamp((o + tt * d - a).dot(ab) / len2, 0.0f, 1.0f);
    p = a + s * ab;
    tt = std::max(0.0f, d.dot(p - o));
  }
  *t = tt;
  *onSegment = p;
  return (o + tt * d - p).norm();
}

}  // namespace

std::optional<NodePick> pickNode(const Session& session, const Vec3& origin, const Vec3& dir, float tolerance,
                                 float maxDistance) {
  if (!(dir.squaredNorm() > 0.0f) || !isFinite(origin) || !isFinite(dir)) return std::nullopt;
  const Vec3 d = dir.normalized();
  std::optional<NodePick> best;
  const std::vector<plant::PlantModel> plants = session.plants();
  for (size_t pi = 0; pi < plants.size(); ++pi) {
    const plant::PlantModel& m = plants[pi];
    for (size_t n = 0; n < m.nodeCount(); ++n) {
      float t = 0.0f;
      Vec3 point;
      const float dist = raySegment(origin, d, m.position[n], m.tip(n), &t, &point);
      if (dist > std::max(m.radius[n], tolerance) || t > maxDistance) continue;
      if (best && !(t < best->t)) continue;
      best = NodePick{uint32_t(pi), uint32_t(n), kNoParticle, point, t};
    }
  }
  if (best)
    if (const models::Grip* g = session.system(best->plant).grip()) {
      const std::vector<uint32_t> ids = g->nodeHandles(session.indexInSystem(best->plant));
      if (best->node < ids.size()) best->particle = ids[best->node];
    }
  return best;
}

std::optional<env::RayHit> pickSurface(const Session& session, const Vec3& origin, const Vec3& dir,
                                       float maxDistance) {
  if (!(dir.squaredNorm() > 0.0f) || !isFinite(origin) || !isFinite(dir)) return std::nullopt;
  return session.environment().rayCast(origin, dir.normalized(), maxDistance);
}

Vec3 seedDirection(const Session& session, const env::RayHit& hit, const Vec3& dir) {
  const Vec3 normal = hit.normal.dot(dir) > 0.0f ? Vec3(-hit.normal) : hit.normal;
  if (!hit.onStem()) return normal;
  Vec3 up = Vec3::UnitY() - Vec3::UnitY().dot(normal) * normal;
  if (up.norm() > 0.2f) return up.normalized();
  const env::StemTube& t = session.environment().stem(hit.stem());
  Vec3 along = (t.b - t.a) - (t.b - t.a).dot(normal) * normal;
  return along.norm() > 1e-6f ? Vec3(along.normalized()) : anyPerpendicular(normal);
}

}  // namespace tendril::session
