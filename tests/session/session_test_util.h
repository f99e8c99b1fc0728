// Small scenes of every model for the session tests, built with their JSON document so that
// they can be saved to session files.
#pragma once

#include "support/test_paths.h"
#include "tendril/core/json_reader.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <fmt/format.h>

#include <memory>
#include <string>

namespace tendril::test {

// A ground plane, a wall behind the seeds and a light; `plants` and `wind` are JSON text.
inline std::string sessionScene(const std::string& plants, const std::string& wind = "") {
  return std::string(R"({"tendril": 1, "seed": 7, "steps": 40, "environment": {"obstacles": [
      {"name": "ground", "type": "plane", "size": [3, 3]},
      {"name": "wall", "type": "wall", "size": [2, 1.5, 0.1], "position": [0, 0, -0.05]}],
      "lights": [{"type": "directional", "direction": [0.3, -1, -0.4]}])") +
         (wind.empty() ? "" : ", \"wind\": " + wind) + R"(}, "plants": [)" + plants + "]}";
}

inline const std::string kClimbPlant = R"({"name": "ivy", "model": "climb", "position": [0, 0, 0.1]})";
inline const std::string kParticlePlant =
    R"({"name": "sprout", "model": "particles", "species": "ivy-particles", "position": [0.1, 0, 0.1]})";
inline const std::string kLSystemPlant =
    R"({"name": "weed", "model": "lsystem", "grammar": "examples/grammars/abop-1.24a.ls", "derivation_length": 4,
        "position": [0.5, 0, 0.4]})";
inline const std::string kGraphPlant =
    R"({"name": "fig", "model": "graph", "graph": "examples/graphs/fig2.json", "position": [-0.6, 0, 0.5]})";
inline const std::string kSphWind = R"({"mode": "sph", "velocity": [0.5, 0, 0],
    "emitters": [{"position": [-0.5, 0.3, 0.2], "direction": [1, 0, 0], "speed": 2, "radius": 0.1}],
    "sph": {"domain_min": [-0.6, 0.0, 0.0], "domain_max": [0.6, 0.6, 0.5], "spacing": 0.06}})";
// The same air with the position-based solver (its pressures are part of the saved state).
inline const std::string kSphWindPositionBased = R"({"mode": "sph", "velocity": [0.5, 0, 0],
    "emitters": [{"position": [-0.5, 0.3, 0.2], "direction": [1, 0, 0], "speed": 2, "radius": 0.1}],
    "sph": {"domain_min": [-0.6, 0.0, 0.0], "domain_max": [0.6, 0.6, 0.5], "spacing": 0.06,
            "solver": "position-based"}})";

inline std::unique_ptr<session::Session> makeSession(const std::string& json, const std::string& source = "test.json") {
  Json doc = parseJson(json, source);
  scene::Scene s = scene::parseScene(doc, source, sourceDir());
  return std::make_unique<session::Session>(std::move(s), std::move(doc), sourceDir());
}

// A closed box from `lo` to `hi` as OBJ text (outward quads): a mesh for add_obstacle.
inline std::string boxObj(const Vec3& lo, const Vec3& hi) {
  std::string s;
  for (int i = 0; i < 8; ++i)
    s += fmt::format("v {} {} {}\n", (i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  s += "f 2 4 8 6\nf 1 5 7 3\nf 3 7 8 4\nf 1 2 6 5\nf 5 6 8 7\nf 1 3 4 2\n";
  return s;
}

}  // namespace tendril::test
