// One reader per settings type: the same light, emitter or stroke JSON fed to the scene
// reader, the edit-script reader and session loading gives the same value in the environment,
// or the same one-line error (after each format's own place: "/environment/lights/0",
// "/edits/0", the saved state's "/lights/0").
#include "session/session_test_util.h"
#include "tendril/core/error.h"
#include "tendril/climb/species_schema.h"
#include "tendril/core/schema.h"
#include "tendril/particles/species_schema.h"
#include "tendril/scene/settings_schema.h"
#include "tendril/session/edit.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/session_file.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <map>
#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>

namespace tendril {
namespace {

enum class Type { Light, Emitter, Stroke };

// The scene with `value` as its only light, stroke or emitter (the others as sessionScene has them).
std::string sceneWith(Type type, const std::string& value) {
  const std::string obstacles = R"([{"name": "ground", "type": "plane", "size": [3, 3]}])";
  std::string env = R"({"obstacles": )" + obstacles;
  if (type == Type::Light) env += R"(, "lights": [)" + value + "]";
  else env += R"(, "lights": [{"type": "directional", "direction": [0.3, -1, -0.4]}])";
  if (type == Type::Stroke) env += R"(, "strokes": [)" + value + "]";
  if (type == Type::Emitter) env += R"(, "wind": {"emitters": [)" + value + "]}";
  return R"({"tendril": 1, "seed": 7, "environment": )" + env + R"(}, "plants": []})";
}

// The scene without the value: what edits start from.
std::string plainScene() { return sceneWith(Type::Light, R"({"type": "directional", "direction": [0.3, -1, -0.4]})"); }

// `value`'s keys in an edit of the type: move_light 0, add_emitter, paint_stroke.
std::string editWith(Type type, const std::string& value) {
  const char* head = type == Type::Light ? R"("edit": "move_light", "light": 0)"
                     : type == Type::Emitter ? R"("edit": "add_emitter")"
                                             : R"("edit": "paint_stroke")";
  Json v = parseJson(value, "value");
  Json e = parseJson(std::string("{\"at_step\": 0, ") + head + "}", "edit");
  for (auto it = v.begin(); it != v.end(); ++it) e[it.key()] = it.value();
  return R"({"tendril_edits": 1, "edits": [)" + e.dump() + "]}";
}

// What the environment holds of the type, as JSON (every field, bit for bit).
Json valueIn(const session::Session& s, Type type) {
  const env::Environment& env = s.environment();
  if (type == Type::Light) return scene::lightJson(env.lights().at(0));
  if (type == Type::Emitter) return scene::emitterJson(env.windField().settings().emitters.at(0));
  return scene::strokeJson(env.strokes().at(0));
}

// The error's text after the first occurrence of `place`.
std::string after(const std::string& what, const std::string& place) {
  const size_t at = what.find(place);
  return at == std::string::npos ? "<" + what + ">" : what.substr(at + place.size());
}

struct Outcome {
  Json value;         // the environment's value, when read
  std::string error;  // else the error after its place, e.g. "/speed: must be in [0, 1000], got 2000"
};

const char* scenePlace(Type type) {
  return type == Type::Light ? "/environment/lights/0" : type == Type::Emitter ? "/environment/wind/emitters/0"
                                                                             : "/environment/strokes/0";
}

Outcome fromScene(Type type, const std::string& value) {
  const char* place = scenePlace(type);
  try {
    auto s = test::makeSession(sceneWith(type, value), "scene.json");
    return {valueIn(*s, type), ""};
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("scene.json:" + std::string(place), 0), 0u) << e.what();
    return {Json(), after(e.what(), place)};
  }
}

Outcome fromEdit(Type type, const std::string& value) {
  try {
    const session::EditScript script = session::parseEditScript(parseJson(editWith(type, value), "edits.json"), "edits.json");
    auto s = test::makeSession(plainScene());
    session::Editor editor(*s);
    session::runEditScript(editor, script);
    // The edited session saved and loaded back holds the same value.
    const std::filesystem::path file = test::scratchDir() / "edited.tses";
    session::saveSession(file, *s, editor.journal());
    EXPECT_EQ(valueIn(*session::loadSession(file).session, type), valueIn(*s, type));
    return {valueIn(*s, type), ""};
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("edits.json:/edits/0", 0), 0u) << e.what();
    return {Json(), after(e.what(), "/edits/0")};
  }
}

// Session loading: a session file holding the value, saved and loaded back. A value the scene
// reader refuses cannot be in a session made from it; such a file is made from the plain scene
// with the value in its stored document (loadSession reads the scene document again).
Outcome fromSessionFile(Type type, const std::string& value) {
  const auto dir = test::scratchDir();
  const std::filesystem::path file = dir / "s.tses";
  std::unique_ptr<session::Session> s;
  try {
    s = test::makeSession(sceneWith(type, value), "scene.json");
  } catch (const Error&) {
    Json doc = parseJson(sceneWith(type, value), "scene.json");
    scene::Scene plain = scene::parseScene(parseJson(plainScene(), "scene.json"), "scene.json", test::sourceDir());
    s = std::make_unique<session::Session>(std::move(plain), std::move(doc), test::sourceDir());
  }
  session::saveSession(file, *s);
  try {
    session::LoadedSession loaded = session::loadSession(file);
    return {valueIn(*loaded.session, type), ""};
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(file.string() + ":", 0), 0u) << e.what();
    return {Json(), after(e.what(), scenePlace(type))};
  }
}

// The value with its keys set as given, whatever the limits (for a saved state holding it).
template <class T>
T unchecked(const schema::Schema<T>& s, T v, const std::string& value) {
  const Json j = parseJson(value, "value");
  for (auto it = j.begin(); it != j.end(); ++it) {
    const schema::Field<T>* f = s.find(it.key());
    if (f && it.value().is_number()) schema::setFileValue(*f, v, it.value().get<double>());
  }
  return v;
}

// Session loading of a saved state holding the value out of range: its check names the field
// with the readers' message.
std::string fromSavedState(Type type, const std::string& value) {
  auto a = test::makeSession(plainScene());
  env::Environment& env = a->environment();
  if (type == Type::Light) {
    env::Light base;
    env.setLights({unchecked(scene::lightSchema(), base, value)});
  } else if (type == Type::Emitter) {
    env::WindEmitter base;
    a->setEmitters({unchecked(scene::emitterSchema(), base, value)});
  } else {
    env::Stroke base;
    base.points = {Vec3(0.1f, 0.2f, 0.0f)};
    env.setStrokes({unchecked(scene::strokeSchema(), base, value)});
  }
  const std::vector<uint8_t> state = a->saveState();
  auto b = test::makeSession(plainScene());
  try {
    b->loadState(state, "state");
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    const char* place = type == Type::Light ? "/lights/0" : type == Type::Emitter ? "/emitters/0" : "/strokes/0";
    return after(e.what(), place);
  }
  return "no error";
}

struct Case {
  Type type;
  std::string value;
  std::string error;       // "" = reads
  bool savedState = false;  // an out-of-range number a saved state can hold
};

const Case kCases[] = {
    // Lights.
    {Type::Light, R"({"type": "directional", "direction": [0.2, -1, 0.1], "intensity": 0.5, "angular_radius": 2.5})", ""},
    {Type::Light, R"({"type": "point", "position": [0.5, 2, 1], "intensity": 2, "samples": 3})", ""},
    {Type::Light, R"({"direction": [0, -3, 1], "angular_radius": 45})", ""},
    {Type::Light, R"({"angular_radius": 50})", "/angular_radius: must be in [0, 45], got 50", true},
    {Type::Light, R"({"intensity": 2000000})", "/intensity: must be in [0, 1000000], got 2000000", true},
    {Type::Light, R"({"samples": 300})", "/samples: must be in [1, 256], got 300", true},
    {Type::Light, R"({"intensity": "bright"})", "/intensity: expected a number, got string \"bright\""},
    {Type::Light, R"({"type": "spot"})", "/type: must be one of \"directional\", \"point\", got \"spot\""},
    {Type::Light, R"({"intensty": 1})", "/intensty: unknown key \"intensty\" (did you mean \"intensity\"?)"},
    {Type::Light, R"({"type": "point"})", "/position: is required for a point light"},
    {Type::Light, R"({"direction": [0, 0, 0]})", "/direction: must be a non-zero direction"},
    {Type::Light, R"({"angle": 2})",
     "/angle: unknown key \"angle\" (a light's angular radius is \"angular_radius\", in degrees)"},
    // Wind emitters.
    {Type::Emitter, R"({"position": [0.2, 0.5, 0.3], "direction": [1, 0.2, 0], "speed": 7, "spread": 12.5, "reach": 4})", ""},
    {Type::Emitter, R"({"position": [0, 1, 0], "speed": 1000, "radius": 0.0001, "spread": 89, "rate": 1e9})", ""},
    {Type::Emitter, R"({"position": [0, 0.5, 0], "speed": 2000})", "/speed: must be in [0, 1000], got 2000", true},
    {Type::Emitter, R"({"position": [0, 0.5, 0], "spread": 89.5})", "/spread: must be in [0, 89], got 89.5", true},
    {Type::Emitter, R"({"position": [0, 0.5, 0], "radius": 0})", "/radius: must be in [0.0001, 1000], got 0", true},
    {Type::Emitter, R"({"speed": 3})", "/position: is required (the emitter's centre, [x, y, z] in m)"},
    {Type::Emitter, R"({"position": "here"})", "/position: expected an array of 3 numbers, got string \"here\""},
    {Type::Emitter, R"({"position": [0, 0, 0], "direction": [0, 0, 0]})", "/direction: must be a non-zero direction"},
    {Type::Emitter, R"({"position": [0, 0, 0], "sped": 3})", "/sped: unknown key \"sped\" (did you mean \"speed\"?)"},
    // Painted strokes.
    {Type::Stroke, R"({"kind": "repel", "radius": 0.2, "strength": 3, "points": [[0.1, 0.5, 0.01], [0.2, 0.6, 0.01]]})", ""},
    {Type::Stroke, R"({"points": [[0.1, 0.5, 0.01]]})", ""},
    {Type::Stroke, R"({"radius": 0, "points": [[0, 0, 0]]})", "/radius: must be in [0.0001, 1000], got 0", true},
    {Type::Stroke, R"({"strength": -1, "points": [[0, 0, 0]]})", "/strength: must be in [0, 1000000], got -1", true},
    {Type::Stroke, R"({"points": []})", "/points: is required: a non-empty array of [x, y, z] points"},
    {Type::Stroke, R"({"points": [[0, 1]]})", "/points/0: expected [x, y, z], got an array"},
    {Type::Stroke, R"({"points": [[0, 2e5, 0]]})", "/points/0: point must be finite and within 100000 m of the origin"},
    {Type::Stroke, R"({"kind": "push", "points": [[0, 0, 0]]})", "/kind: must be one of \"attract\", \"repel\", got \"push\""},
    {Type::Stroke, R"({"radius": "wide", "points": [[0, 0, 0]]})", "/radius: expected a number, got string \"wide\""},
    {Type::Stroke, R"({"points": [[0, 0, 0]], "radus": 1})", "/radus: unknown key \"radus\" (did you mean \"radius\"?)"},
};

TEST(SettingsReaders, SceneEditScriptAndSessionLoadingAgree) {
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.value);
    const Outcome scene = fromScene(c.type, c.value);
    const Outcome edit = fromEdit(c.type, c.value);
    const Outcome loaded = fromSessionFile(c.type, c.value);
    EXPECT_EQ(scene.error, c.error);
    EXPECT_EQ(edit.error, c.error);
    EXPECT_EQ(loaded.error, c.error);
    if (c.error.empty()) {
      EXPECT_FALSE(scene.value.is_null());
      EXPECT_EQ(edit.value, scene.value);
      EXPECT_EQ(loaded.value, scene.value);
    }
    if (c.savedState) {
      EXPECT_EQ(fromSavedState(c.type, c.value), c.error);
    }
  }
}

// Older spellings still read, to the same value: a stroke's "attract": false is "kind": "repel",
// an edit's "translation" is "position".
TEST(SettingsReaders, OlderSpellingsReadTheSame) {
  const std::string points = R"("radius": 0.2, "points": [[0.1, 0.5, 0.01]])";
  EXPECT_EQ(fromEdit(Type::Stroke, R"({"attract": false, )" + points + "}").value,
            fromScene(Type::Stroke, R"({"kind": "repel", )" + points + "}").value);
  EXPECT_EQ(fromEdit(Type::Stroke, R"({"attract": true, )" + points + "}").value,
            fromEdit(Type::Stroke, R"({"kind": "attract", )" + points + "}").value);
  EXPECT_EQ(fromEdit(Type::Stroke, R"({"attract": true, "kind": "attract", )" + points + "}").error,
            "/attract: give \"kind\" or the older \"attract\", not both");

  auto transform = [](const std::string& keys) {
    Json j = parseJson(keys, "t");
    JsonObject o(j, "t");
    RigidTransform t = scene::readTransform(o, false);
    o.finish();
    return t;
  };
  const RigidTransform a = transform(R"({"translation": [1, 2, 3], "rotation": [1, 0, 0, 0]})");
  const RigidTransform b = transform(R"({"position": [1, 2, 3], "rotation": [1, 0, 0, 0]})");
  EXPECT_EQ(a.translation, b.translation);
  EXPECT_EQ(a.rotation.coeffs(), b.rotation.coeffs());
  // Rotation as Euler degrees or as a quaternion, in edits as in scenes.
  const RigidTransform euler = transform(R"({"rotation": [0, 90, 0]})");
  const RigidTransform quat = transform(R"({"rotation": [0.70710678, 0, 0.70710678, 0]})");
  EXPECT_LT((euler.rotation.coeffs() - quat.rotation.coeffs()).norm(), 1e-6f);
  EXPECT_THROW(transform(R"({"rotation": [1, 0]})"), Error);
  EXPECT_THROW(transform(R"({"rotation": [2, 0, 0, 0]})"), Error);
  EXPECT_THROW(transform(R"({"position": [0, 0, 0], "translation": [0, 0, 0]})"), Error);
  // What the writer writes reads back bit for bit.
  Json written = Json::object();
  scene::writeTransform(written, euler);
  const RigidTransform back = transform(written.dump());
  EXPECT_EQ(back.translation, euler.translation);
  EXPECT_EQ(back.rotation.coeffs(), euler.rotation.coeffs());
}

// Every edit of these settings written to JSON reads back to the same value, angles included.
TEST(SettingsReaders, EditsRoundTripBitForBit) {
  for (const Case& c : kCases) {
    if (!c.error.empty()) continue;
    SCOPED_TRACE(c.value);
    const session::EditScript script =
        session::parseEditScript(parseJson(editWith(c.type, c.value), "edits.json"), "edits.json");
    const Json once = session::editToJson(script.edits[0].edit);
    JsonObject o(once, "edit");
    const session::Edit back = session::readEdit(o);
    o.finish();
    EXPECT_EQ(session::editToJson(back), once);
  }
  // A spread that is no round number of degrees survives too.
  session::AddEmitter add;
  add.emitter.spread = 0.123456789f;
  add.emitter.position = Vec3(0.1f, 0.2f, 0.3f);
  const Json j = session::editToJson(add);
  JsonObject o(j, "edit");
  const session::Edit back = session::readEdit(o);
  o.finish();
  EXPECT_EQ(std::get<session::AddEmitter>(back).emitter.spread, add.emitter.spread);
}

// --- every limit the same in the readers and the checks ---

// The error's place and rule, without the value it quotes (JSON and floats print numbers
// differently: "1010.0" and "1010").
std::string rule(const std::string& message) { return message.substr(0, message.find(", got ")); }

// For every bounded number of the schema: at its limits, just past them and between, the reader
// and the check of the same value set directly agree (both accept it, or both refuse it at the
// same key with the same rule), and the value read is the value set.
template <class T>
void expectSameLimits(const schema::Schema<T>& s, const Json& base, const std::function<T(JsonObject&)>& read,
                      const std::string& nest = "") {
  T valid;
  {
    JsonObject o(base, "x");
    valid = read(o);
    o.finish();
  }
  for (const schema::Field<T>& f : s.fields) {
    const bool scalar = f.kind == schema::Kind::Number || f.kind == schema::Kind::Angle || f.kind == schema::Kind::Integer;
    if (!scalar || !std::isfinite(f.min) || !std::isfinite(f.max)) continue;
    const double step = f.kind == schema::Kind::Integer ? 1.0
                        : f.kind == schema::Kind::Angle ? 0.5
                                                        : std::max(std::abs(f.max), 1.0) * 0.01;
    for (double v : {f.min, f.max, f.min - step, f.max + step, 0.5 * (f.min + f.max)}) {
      if (f.kind == schema::Kind::Integer) v = std::floor(v);
      SCOPED_TRACE(fmt::format("{} {} = {}", s.name, f.key, v));
      Json j = base;
      Json* at = &j;
      if (!nest.empty()) at = &j[nest];  // the schema's keys are in this object of `base`
      (*at)[std::string(f.key)] = f.kind == schema::Kind::Integer ? Json(int64_t(v)) : Json(v);
      std::string readError;
      T got = valid;
      try {
        JsonObject o(j, "x");
        got = read(o);
        o.finish();
      } catch (const Error& e) {
        readError = rule(after(e.what(), "x:"));
        readError = readError.substr(readError.rfind('/'));  // the key, not the object it is in
      }
      T direct = valid;
      schema::setFileValue(f, direct, v);
      const std::optional<std::string> bad = schema::check(s, direct);
      EXPECT_EQ(bad ? rule(*bad) : std::string(), readError);
      if (readError.empty()) {
        EXPECT_EQ(schema::fileValue(f, got), schema::fileValue(f, direct));
      }
    }
  }
}

TEST(SettingsReaders, ChecksApplyTheReadersLimits) {
  expectSameLimits<env::Light>(scene::lightSchema(), Json::object(), [](JsonObject& o) { return scene::readLight(o); });
  expectSameLimits<env::WindEmitter>(scene::emitterSchema(), parseJson(R"({"position": [0, 1, 0]})", "j"),
                                     [](JsonObject& o) { return scene::readEmitter(o); });
  expectSameLimits<env::Stroke>(scene::strokeSchema(), parseJson(R"({"points": [[0, 1, 0]]})", "j"),
                                [](JsonObject& o) { return scene::readStroke(o); });
  expectSameLimits<env::WindSettings>(scene::windSchema(), Json::object(),
                                      [](JsonObject& o) { return scene::readWind(o); });
  auto output = [](JsonObject& o) {
    JsonObject copy(o.json(), o.source(), o.pointer());
    for (auto it = o.json().begin(); it != o.json().end(); ++it) o.markRead(it.key());
    return scene::readOutput(copy);
  };
  expectSameLimits<scene::OutputSettings>(scene::outputSchema(), Json::object(), output);
  expectSameLimits<scene::OutputSettings>(scene::windAnimationSchema(), parseJson(R"({"wind_animation": {}})", "j"),
                                          output, "wind_animation");
  auto climbSpecies = [](JsonObject& o) {
    climb::ClimbSpecies s;
    climb::readClimbSpecies(o, s, "");
    return s;
  };
  expectSameLimits<climb::ClimbSpecies>(climb::climbSpeciesSchema(), Json::object(), climbSpecies);
  expectSameLimits<climb::ClimbSpecies>(climb::climbTropismsSchema(), parseJson(R"({"tropisms": {}})", "j"),
                                        climbSpecies, "tropisms");
  expectSameLimits<climb::ClimbSpecies>(climb::climbDecreaseSchema(), parseJson(R"({"decrease": {}})", "j"),
                                        climbSpecies, "decrease");
  expectSameLimits<particles::ParticleSpecies>(particles::particleSpeciesSchema(), Json::object(), [](JsonObject& o) {
    particles::ParticleSpecies s;
    particles::readParticleSpecies(o, s, "");
    return s;
  });
  // The defaults pass the checks, and a value made of them is what an empty object reads.
  EXPECT_FALSE(scene::checkLight(env::Light{}));
  EXPECT_FALSE(scene::checkEmitter(env::WindEmitter{}));
  EXPECT_FALSE(scene::checkWind(env::WindSettings{}));
  Json empty = Json::object();
  JsonObject o(empty, "x");
  const env::WindSettings w = scene::readWind(o);
  o.finish();
  EXPECT_EQ(w.gustTurn, env::WindSettings{}.gustTurn);
  EXPECT_EQ(w.gustStrength, env::WindSettings{}.gustStrength);
  Json emitter = parseJson(R"({"position": [0, 0, 0]})", "j");
  JsonObject e(emitter, "x");
  EXPECT_EQ(scene::readEmitter(e).spread, env::WindEmitter{}.spread);
  e.finish();
}

// --- the docs' tables agree with the schemas ---

std::string readDoc(const std::string& name) {
  std::ifstream in(test::sourceDir() / "docs" / name);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The rows of the first table after the heading line `heading`: key -> the whole row.
std::map<std::string, std::string> tableAfter(const std::string& doc, const std::string& heading) {
  std::map<std::string, std::string> rows;
  const size_t at = doc.find("\n" + heading + "\n");
  EXPECT_NE(at, std::string::npos) << heading;
  if (at == std::string::npos) return rows;
  std::istringstream lines(doc.substr(at + heading.size() + 2));
  std::string line;
  bool inTable = false;
  while (std::getline(lines, line)) {
    if (line.rfind("#", 0) == 0) break;
    if (line.rfind("|", 0) != 0) {
      if (inTable) break;
      continue;
    }
    inTable = true;
    if (line.rfind("| key", 0) == 0 || line.rfind("|---", 0) == 0) continue;
    const size_t open = line.find('`'), close = line.find('`', open + 1);
    if (open == std::string::npos || close == std::string::npos) continue;
    rows[line.substr(open + 1, close - open - 1)] = line;
  }
  return rows;
}

std::string vecText(const Vec3& v) { return fmt::format("`[{}, {}, {}]`", v.x(), v.y(), v.z()); }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// Every key of the schema has a row giving its default, its range and its unit; every row is
// a key of the schema or one of `others`.
template <class T>
void expectTableAgrees(const std::string& docName, const std::vector<std::string>& headings,
                       const schema::Schema<T>& s, std::vector<std::string> others = {}) {
  std::map<std::string, std::string> rows;
  for (const std::string& h : headings) rows.merge(tableAfter(readDoc(docName), h));
  const std::string heading = headings.front();
  // An entry of `others` ending in "." stands for every key it begins ("leaf.").
  auto other = [&](const std::string& key) {
    for (const std::string& o : others)
      if (o == key || (o.back() == '.' && key.rfind(o, 0) == 0)) return true;
    return false;
  };
  for (const auto& [key, row] : rows)
    EXPECT_TRUE(s.find(key) || other(key))
        << docName << " " << heading << ": `" << key << "` is not a key of the " << s.name << " settings";
  for (const schema::Field<T>& f : s.fields) {
    SCOPED_TRACE(docName + " " + heading + " " + std::string(f.key));
    auto it = rows.find(std::string(f.key));
    if (it == rows.end()) {
      ADD_FAILURE() << "no row for `" << f.key << "`";
      continue;
    }
    const std::string& row = it->second;
    std::string expected;
    switch (f.kind) {
      case schema::Kind::Choice: expected = "`" + std::string(f.choices.at(size_t(f.fallback))) + "`"; break;
      case schema::Kind::Vec3:
      case schema::Kind::Direction: expected = vecText(f.fallbackVec); break;
      case schema::Kind::Boolean: expected = f.fallback != 0.0 ? "`true`" : "`false`"; break;
      case schema::Kind::Points: break;
      case schema::Kind::Number:
      case schema::Kind::Angle: expected = fmt::format("`{}`", float(f.fallback)); break;  // as the float it is
      default: expected = "`" + schema::formatNumber(f.fallback) + "`";
    }
    if (f.required) expected = "**required**";
    if (!expected.empty()) {
      EXPECT_TRUE(contains(row, expected)) << "default " << expected << " missing from: " << row;
    }
    const bool worldExtent = f.min == -JsonObject::kWorldExtent && f.max == JsonObject::kWorldExtent;
    if (std::isfinite(f.min) && std::isfinite(f.max) && f.kind != schema::Kind::Boolean &&
        f.kind != schema::Kind::Choice && f.kind != schema::Kind::Seed && !worldExtent) {
      const std::string lo = schema::formatNumber(f.min), hi = schema::formatNumber(f.max);
      EXPECT_TRUE(contains(row, lo + "–" + hi) || contains(row, "[" + lo + ", " + hi + "]"))
          << "range " << lo << "–" << hi << " missing from: " << row;
    }
    if (f.unit == "deg") {
      EXPECT_TRUE(contains(lower(row), "degree")) << "unit degrees missing from: " << row;
    } else if (!f.unit.empty()) {
      EXPECT_TRUE(contains(row, "(" + std::string(f.unit) + ")")) << "unit (" << f.unit << ") missing from: " << row;
    }
  }
}

TEST(SettingsReaders, DocsTablesAgreeWithTheSchemas) {
  expectTableAgrees("scene-format.md", {"### Lights"}, scene::lightSchema());
  expectTableAgrees("scene-format.md", {"### Strokes"}, scene::strokeSchema());
  expectTableAgrees("scene-format.md", {"### Wind"}, scene::windSchema(), {"emitters", "sph"});
  expectTableAgrees("scene-format.md", {"#### Wind emitters"}, scene::emitterSchema());
  expectTableAgrees("scene-format.md", {"## Output"}, scene::outputSchema(), {"wind_animation", "lod_triangles", "impostor"});
  expectTableAgrees("scene-format.md", {"#### Wind animation"}, scene::windAnimationSchema());
  expectTableAgrees("particles.md", {"## Species keys"}, particles::particleSpeciesSchema(), {"leaf.", "bark."});
  expectTableAgrees("species.md", {"### Shoot size (eq. 8)", "### Climbing", "### Branching (§3.7)"},
                    climb::climbSpeciesSchema(), {"decrease", "release_angle", "branch_angle"});
  expectTableAgrees("species.md", {"### Tropisms (eq. 3–4, 6–7)"}, climb::climbTropismsSchema());
}

// The JSON examples of docs/edit-scripts.md are edits the reader takes, and the scene format's
// light examples are lights.
TEST(SettingsReaders, DocsExamplesRead) {
  const std::string doc = readDoc("edit-scripts.md");
  const size_t from = doc.find("\n## The edits");
  ASSERT_NE(from, std::string::npos);
  const size_t to = doc.find("\n## ", from + 5);
  size_t at = from;
  int blocks = 0;
  while ((at = doc.find("```json\n", at)) != std::string::npos && at < to) {
    const size_t end = doc.find("```", at + 8);
    const std::string block = doc.substr(at + 8, end - at - 8);
    SCOPED_TRACE(block);
    EXPECT_NO_THROW(session::parseEditScript(
        parseJson(R"({"tendril_edits": 1, "edits": [)" + block + "]}", "edit-scripts.md"), "edit-scripts.md"));
    at = end + 3;
    ++blocks;
  }
  EXPECT_GE(blocks, 10);

  const std::string scene = readDoc("scene-format.md");
  const size_t lights = scene.find("```json\n", scene.find("\n### Lights\n"));
  std::istringstream lines(scene.substr(lights + 8, scene.find("```", lights + 8) - lights - 8));
  std::string line;
  int read = 0;
  while (std::getline(lines, line)) {
    SCOPED_TRACE(line);
    EXPECT_EQ(fromScene(Type::Light, line).error, "");
    ++read;
  }
  EXPECT_EQ(read, 2);
}

}  // namespace
}  // namespace tendril
