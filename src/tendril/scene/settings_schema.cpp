#include "tendril/scene/settings_schema.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace tendril::scene {

using env::Light;
using env::Stroke;
using env::WindEmitter;
using env::WindSettings;
namespace s = schema;

const s::Schema<Light>& lightSchema() {
  static const s::Schema<Light> schema{
      "light",
      {
          s::choice<Light>(
              "type", {"directional", "point"}, 0, [](const Light& l) { return int(l.type); },
              [](Light& l, int i) { l.type = i == 1 ? Light::Type::Point : Light::Type::Directional; }, "type",
              "`directional` (sun) or `point`"),
          s::direction<Light>("direction", &Light::direction, Vec3(-0.3f, -1.0f, -0.4f), "direction",
                              "directional: the direction the light travels (normalised)"),
          s::vec3<Light>("position", &Light::position, Vec3::Zero(), -JsonObject::kWorldExtent,
                         JsonObject::kWorldExtent, "m", "position", "point: where the light is; required for `point`"),
          s::number<Light>("intensity", &Light::intensity, 1.0, 0.0, 1e6, "", "intensity",
                           "relative weight among the lights")
              .slider(0.0, 4.0),
          s::angle<Light>("angular_radius", &Light::angularRadius, 0.0, 0.0, 45.0, "angular radius",
                          "angular radius of the light, for soft shadows"),
          s::integer<Light>("samples", &Light::samples, 1, 1, 256, "samples",
                            "shadow rays per query; `8` if `angular_radius` > 0, else `1`"),
      }};
  return schema;
}

const s::Schema<WindEmitter>& emitterSchema() {
  static const s::Schema<WindEmitter> schema{
      "wind emitter",
      {
          s::vec3<WindEmitter>("position", &WindEmitter::position, Vec3::Zero(), -JsonObject::kWorldExtent,
                               JsonObject::kWorldExtent, "m", "position", "the emitter's centre, [x, y, z] in m")
              .require(),
          s::direction<WindEmitter>("direction", &WindEmitter::direction, Vec3::UnitX(), "direction",
                                    "the direction it blows (normalised)"),
          s::number<WindEmitter>("speed", &WindEmitter::speed, 5.0, 0.0, 1000.0, "m/s", "speed",
                                 "air speed at the nozzle")
              .slider(0.0, 30.0),
          s::number<WindEmitter>("radius", &WindEmitter::radius, 0.5, 1e-4, 1000.0, "m", "radius",
                                 "radius of the nozzle")
              .slider(0.01, 5.0),
          s::number<WindEmitter>("reach", &WindEmitter::reach, 10.0, 0.0, 1e6, "m", "reach",
                                 "length of the jet along its direction")
              .slider(0.1, 50.0),
          s::angle<WindEmitter>("spread", &WindEmitter::spread, 8.0, 0.0, 89.0, "spread",
                                "half-angle the jet widens by")
              .slider(0.0, 45.0),
          s::number<WindEmitter>("rate", &WindEmitter::rate, 0.0, 0.0, 1e9, "1/s", "rate",
                                 "air particles per second in `sph` mode (`0`: from speed and area)"),
      }};
  return schema;
}

const s::Schema<Stroke>& strokeSchema() {
  static const s::Schema<Stroke> schema{
      "stroke",
      {
          s::choice<Stroke>(
              "kind", {"attract", "repel"}, 0, [](const Stroke& st) { return st.attract ? 0 : 1; },
              [](Stroke& st, int i) { st.attract = i == 0; }, "kind",
              "`attract` or `repel` (edit scripts before this build: `\"attract\": true` or `false`, still read)"),
          s::number<Stroke>("radius", &Stroke::radius, 0.3, 1e-4, 1e3, "m", "radius", "reach of each point"),
          s::number<Stroke>("strength", &Stroke::strength, 1.0, 0.0, 1e6, "", "strength", "how strongly it acts"),
          s::points<Stroke>("points", &Stroke::points, "points", "non-empty array of `[x, y, z]` on surfaces"),
      }};
  return schema;
}

const s::Schema<WindSettings>& windSchema() {
  static const s::Schema<WindSettings> schema{
      "wind",
      {
          s::choice<WindSettings>(
              "mode", {"constant", "gusty", "sph"}, 0, [](const WindSettings& w) { return int(w.mode); },
              [](WindSettings& w, int i) {
                w.mode = i == 1 ? env::WindMode::Gusty : i == 2 ? env::WindMode::Sph : env::WindMode::Constant;
              },
              "mode", "`constant`, `gusty` or `sph` (simulated air)"),
          s::vec3<WindSettings>("velocity", &WindSettings::velocity, Vec3::Zero(), -200.0, 200.0, "m/s", "velocity",
                                "prevailing wind"),
          s::number<WindSettings>("gust_strength", &WindSettings::gustStrength, 0.4, 0.0, 1.0, "", "gust strength",
                                  "gusty: fraction of the prevailing speed gusts add or take away"),
          s::number<WindSettings>("gust_period", &WindSettings::gustPeriod, 3.0, 0.05, 3600.0, "s", "gust period",
                                  "gusty: seconds between independent gusts"),
          s::number<WindSettings>("gust_scale", &WindSettings::gustScale, 6.0, 0.01, 1e4, "m", "gust scale",
                                  "gusty: metres across the wind between independent gusts"),
          s::angle<WindSettings>("gust_turn", &WindSettings::gustTurn, 12.0, 0.0, 90.0, "gust turn",
                                 "gusty: how far the direction wanders about +Y"),
          s::seed<WindSettings>("seed", &WindSettings::seed, 0, "seed", "seed of the gust noise"),
      }};
  return schema;
}

const s::Schema<OutputSettings>& outputSchema() {
  static const s::Schema<OutputSettings> schema{
      "output",
      {
          s::integer<OutputSettings>("radial_segments", &OutputSettings::radialSegments, 8, 3, 64, "radial segments",
                                     "vertices around each branch"),
          s::integer<OutputSettings>("subdivisions", &OutputSettings::subdivisions, 3, 1, 16, "subdivisions",
                                     "spline samples per segment"),
          s::boolean<OutputSettings>("include_obstacles", &OutputSettings::includeObstacles, false,
                                     "include obstacles", "write the obstacles into the exported files too"),
          s::integer<OutputSettings>("lods", &OutputSettings::lods, 1, 1, 8, "levels of detail",
                                     "levels of detail per plant, LOD0 included (`1`: none)"),
          s::number<OutputSettings>("lod_ratio", &OutputSettings::lodRatio, 0.45, 0.01, 1.0, "", "LOD ratio",
                                    "LODk's triangle budget: LOD0's triangles × lod_ratio^k"),
          s::boolean<OutputSettings>("leaf_atlas", &OutputSettings::leafAtlas, false, "leaf atlas",
                                     "pack each plant's leaf textures into one atlas: its leaves are one material"),
          s::boolean<OutputSettings>("wind_data", &OutputSettings::windData, false, "engine wind data",
                                     "per-vertex wind attributes in the .glb for a game engine's shader"),
          s::boolean<OutputSettings>("instancing", &OutputSettings::instancing, false, "GPU instancing",
                                     "repeated primitive shapes written once, drawn per copy by "
                                     "EXT_mesh_gpu_instancing in the .glb, where that makes it smaller"),
          s::boolean<OutputSettings>("maps", &OutputSettings::maps, false, "normal and roughness maps",
                                     "bark normal and roughness maps and leaf normal maps made with their textures"),
          s::boolean<OutputSettings>("pivot_painter", &OutputSettings::pivotPainter, false, "Pivot Painter textures",
                                     "per plant a Pivot Painter 2 pair of textures (pivots and parents, axes and "
                                     "extents) beside the .glb, indexed by its TEXCOORD_1"),
      }};
  return schema;
}

const s::Schema<OutputSettings>& windAnimationSchema() {
  static const s::Schema<OutputSettings> schema{
      "wind animation",
      {
          s::number<OutputSettings>("seconds", &OutputSettings::animationSeconds, 4.0, 0.1, 600.0, "s", "seconds",
                                    "length of the loop"),
          s::integer<OutputSettings>("fps", &OutputSettings::animationFps, 24, 1, 240, "frames per second",
                                     "keyframes per second"),
          s::integer<OutputSettings>("joints", &OutputSettings::animationJoints, 128, 1, 1024, "joints",
                                     "joints per plant's skin"),
      }};
  return schema;
}

// --- readers ---

Light readLight(JsonObject& o) {
  if (o.has("angle"))
    throw o.error("angle", "unknown key \"angle\" (a light's angular radius is \"angular_radius\", in degrees)");
  Light l = s::read(o, lightSchema());
  if (l.type == Light::Type::Point && !o.has("position")) throw o.error("position", "is required for a point light");
  if (!o.has("samples") && l.angularRadius > 0.0f) l.samples = 8;
  return l;
}

WindEmitter readEmitter(JsonObject& o) { return s::read(o, emitterSchema()); }

Stroke readStroke(JsonObject& o) {
  const bool older = o.has("attract");  // edit scripts' spelling before "kind"
  if (older && o.has("kind")) throw o.error("attract", "give \"kind\" or the older \"attract\", not both");
  Stroke st = s::read(o, strokeSchema());
  if (older) st.attract = o.boolean("attract", true);
  return st;
}

WindSettings readWind(JsonObject& o) {
  WindSettings w = s::read(o, windSchema());
  for (JsonObject& e : o.objectArray("emitters")) {
    w.emitters.push_back(readEmitter(e));
    e.finish();
  }
  return w;
}

OutputSettings readOutput(JsonObject& o) {
  OutputSettings out;
  s::readOver(o, outputSchema(), out);
  // Explicit triangle budgets of LOD1, LOD2, ... in place of lod_ratio (mesh/lod.h); "lods"
  // defaults to one more than their number.
  if (const Json* t = o.find("lod_triangles")) {
    const std::string key = "lod_triangles";
    if (o.has("lod_ratio")) throw o.error(key, "give \"lod_ratio\" or \"lod_triangles\", not both");
    if (!t->is_array() || t->empty())
      throw o.error(key, "expected a non-empty array of triangle counts, got " + describeJson(*t));
    if (!o.has("lods")) {
      if (t->size() > 7) throw o.error(key, fmt::format("has {} budgets; at most 7 (lods is at most 8)", t->size()));
      out.lods = int(t->size()) + 1;
    }
    if (t->size() != size_t(out.lods - 1))
      throw o.error(key, fmt::format("has {} budget(s) but \"lods\" is {}: give one per level below LOD0 ({})",
                                     t->size(), out.lods, out.lods - 1));
    for (size_t i = 0; i < t->size(); ++i) {
      const Json& e = (*t)[i];
      const std::string at = o.pointerTo(key) + "/" + std::to_string(i);
      if (!e.is_number_integer() || e.get<int64_t>() < 1)
        throw Error(o.source(), at, "expected a positive whole number of triangles, got " + e.dump());
      out.lodTriangles.push_back(e.get<uint64_t>());
      if (i > 0 && out.lodTriangles[i] > out.lodTriangles[i - 1])
        throw Error(o.source(), at,
                    fmt::format("must not exceed the budget of the level above ({}), got {}", out.lodTriangles[i - 1],
                                out.lodTriangles[i]));
    }
  }
  // The impostor: true / false, or an object (io/impostor.h's settings).
  if (const Json* imp = o.find("impostor")) {
    if (imp->is_boolean()) {
      out.impostor = imp->get<bool>();
    } else if (imp->is_object()) {
      JsonObject i(*imp, o.source(), o.pointerTo("impostor"));
      out.impostor = i.boolean("enabled", true);
      out.impostorSlabs = int(i.integer("slabs", 8, 1, 16));
      out.impostorResolution = int(i.integer("resolution", 256, 16, 2048));
      i.finish();
    } else {
      throw o.error("impostor", "expected true, false or an object with \"slabs\" and \"resolution\", got " +
                                    describeJson(*imp));
    }
  }
  if (auto a = o.optionalObject("wind_animation")) {
    s::setDefaults(windAnimationSchema(), out);
    s::readOver(*a, windAnimationSchema(), out);
    a->finish();
  }
  o.finish();
  return out;
}

// --- writers and checks ---

Json lightJson(const Light& l) { return s::write(lightSchema(), l); }
Json emitterJson(const WindEmitter& e) { return s::write(emitterSchema(), e); }
Json strokeJson(const Stroke& st) { return s::write(strokeSchema(), st); }

std::optional<std::string> checkLight(const Light& l) { return s::check(lightSchema(), l); }
std::optional<std::string> checkEmitter(const WindEmitter& e) { return s::check(emitterSchema(), e); }
std::optional<std::string> checkStroke(const Stroke& st) { return s::check(strokeSchema(), st); }

std::optional<std::string> checkWind(const WindSettings& w) {
  if (auto bad = s::check(windSchema(), w)) return bad;
  for (size_t i = 0; i < w.emitters.size(); ++i)
    if (auto bad = checkEmitter(w.emitters[i])) return fmt::format("/emitters/{}{}", i, *bad);
  return std::nullopt;
}

Light normalised(Light l) {
  l.direction.normalize();
  return l;
}

WindEmitter normalised(WindEmitter e) {
  e.direction.normalize();
  return e;
}

// --- transforms ---

RigidTransform readTransform(JsonObject& o, bool normalise) {
  RigidTransform t;
  if (o.has("translation")) {
    if (o.has("position")) throw o.error("translation", "give \"position\" or the older \"translation\", not both");
    t.translation = o.vec3("translation", Vec3::Zero());
  } else {
    t.translation = o.vec3("position", Vec3::Zero());
  }
  if (const Json* r = o.find("rotation")) {
    auto numbers = [&] {
      for (const Json& e : *r)
        if (!e.is_number()) return false;
      return true;
    };
    if (r->is_array() && r->size() == 3) {
      t.rotation = quatFromEulerDegrees(o.vec3("rotation", Vec3::Zero(), -3600.0, 3600.0));
    } else if (r->is_array() && r->size() == 4 && numbers()) {
      Quat q((*r)[0].get<float>(), (*r)[1].get<float>(), (*r)[2].get<float>(), (*r)[3].get<float>());
      if (!(std::abs(q.norm() - 1.0f) < 1e-3f)) throw o.error("rotation", "is not a unit quaternion [w, x, y, z]");
      if (normalise) q.normalize();
      t.rotation = q;
    } else {
      throw o.error("rotation", "expected [x, y, z] Euler angles in degrees or a unit quaternion [w, x, y, z], got " +
                                    describeJson(*r));
    }
  }
  return t;
}

void writeTransform(Json& j, const RigidTransform& t) {
  const Quat& q = t.rotation;
  j["position"] = Json::array({t.translation.x(), t.translation.y(), t.translation.z()});
  j["rotation"] = Json::array({q.w(), q.x(), q.y(), q.z()});
}

}  // namespace tendril::scene
