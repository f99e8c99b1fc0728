// Scenes with simulated air: the scene's emitters feed the SPH air, the wind field samples it,
// and its settings are checked.
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace tendril {
namespace {

TEST(SphScene, EmittersFeedTheAirTheWindFieldSamples) {
  const char* json = R"({"tendril": 1, "seed": 2, "environment": {
      "obstacles": [{"name": "ground", "type": "plane", "size": [4, 4]}],
      "wind": {"mode": "sph", "velocity": [0, 0, 0],
               "emitters": [{"position": [-0.5, 0.4, 0], "direction": [1, 0, 0], "speed": 3, "radius": 0.15}],
               "sph": {"domain_min": [-0.6, 0.0, -0.4], "domain_max": [0.6, 0.8, 0.4], "spacing": 0.05,
                       "fill": false}}},
    "plants": [{"name": "sprout", "model": "particles", "species": "ivy-particles", "position": [0.2, 0, 0]}]})";
  scene::Scene s = scene::parseScene(parseJson(json, "sph scene"), "sph scene", test::sourceDir());
  session::Session session(std::move(s));
  EXPECT_EQ(session.environment().wind(Vec3(-0.3f, 0.4f, 0), 0.0f), Vec3::Zero());  // no air yet
  session.run(20);
  Vec3 w = session.environment().wind(Vec3(-0.3f, 0.4f, 0), 0.5f);
  EXPECT_GT(w.x(), 1.0f) << w.transpose();  // the jet's air has arrived
  EXPECT_LT(std::fabs(w.y()) + std::fabs(w.z()), w.x());
}

TEST(SphScene, SettingsAreChecked) {
  auto parse = [](const std::string& wind) {
    std::string json = R"({"tendril": 1, "environment": {"wind": )" + wind + "}}";
    return scene::parseScene(parseJson(json, "s.json"), "s.json", test::sourceDir());
  };
  auto message = [&](const std::string& wind) {
    try {
      parse(wind);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(R"({"mode": "sph"})").find("/environment/wind/sph"), std::string::npos);
  EXPECT_NE(message(R"({"mode": "gusty", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1]}})").find("only applies"),
            std::string::npos);
  EXPECT_NE(message(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,0,1]}})").find("domain_max"),
            std::string::npos);
  EXPECT_NE(message(R"({"mode": "windy"})").find("/environment/wind/mode"), std::string::npos);
  EXPECT_NE(message(R"({"velocity": [1, 0, 0], "gust": 1})").find("gust"), std::string::npos);
  EXPECT_NE(message(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1], "boundary": {"+w": "closed"}}})")
                .find("/environment/wind/sph/boundary"),
            std::string::npos);
  EXPECT_NE(message(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1], "boundary": {"+x": "shut"}}})")
                .find("/environment/wind/sph/boundary/+x"),
            std::string::npos);
  EXPECT_NO_THROW(parse(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1], "boundary": "closed"}})"));
  // A wind tunnel: every face closed but the outlet.
  scene::Scene tunnel = parse(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1],
      "boundary": {"-x": "closed", "-y": "closed", "+y": "closed", "-z": "closed", "+z": "closed"}}})");
  for (int f = 0; f < 6; ++f) EXPECT_EQ(tunnel.sph.closed(f), f != 1) << f;
  EXPECT_TRUE(parse(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1], "boundary": "closed"}})")
                  .sph.allClosed());
  // The solver and its iterations.
  const scene::Scene pbf =
      parse(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1], "solver": "position-based",
                "iterations": 4}})");
  EXPECT_EQ(pbf.sph.solver, wind::SphSolver::PositionBased);
  EXPECT_EQ(pbf.sph.iterations, 4);
  EXPECT_EQ(parse(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1]}})").sph.solver,
            wind::SphSolver::WeaklyCompressible);
  EXPECT_NE(message(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1], "solver": "implicit"}})")
                .find("/environment/wind/sph/solver"),
            std::string::npos);
  EXPECT_NE(message(R"({"mode": "sph", "sph": {"domain_min": [0,0,0], "domain_max": [1,1,1], "iterations": 0}})")
                .find("/environment/wind/sph/iterations"),
            std::string::npos);
}

// What only the air itself can check — an emitter outside its domain, a domain of too many
// cells, a fill beyond max_particles — is named in the scene file too, not as "SPH ...".
TEST(SphScene, WhatTheAirRefusesIsNamedInTheScene) {
  auto message = [](const std::string& sph, const std::string& emitter) {
    std::string json = R"({"tendril": 1, "environment": {"wind": {"mode": "sph", "velocity": [2, 0, 0], "sph": )" + sph +
                       R"(, "emitters": [{"position": [0.1, 0.5, 0.5]}, )" + emitter + "]}}}";
    try {
      scene::Scene s = scene::parseScene(parseJson(json, "air.json"), "air.json", test::sourceDir());
      session::Session session(std::move(s));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string box = R"({"domain_min": [0, 0, 0], "domain_max": [1, 1, 1], "fill": false})";
  const std::string inside = R"({"position": [0.2, 0.5, 0.5]})";
  EXPECT_EQ(message(box, inside), "no error");
  EXPECT_NE(message(box, R"({"position": [5, 0.5, 0.5]})").find("air.json:/environment/wind/emitters/1/position:"),
            std::string::npos)
      << message(box, R"({"position": [5, 0.5, 0.5]})");
  const std::string huge = R"({"domain_min": [0, 0, 0], "domain_max": [900, 900, 900], "spacing": 0.05, "fill": false})";
  EXPECT_NE(message(huge, inside).find("air.json:/environment/wind/sph/domain_max:"), std::string::npos)
      << message(huge, inside);
  const std::string crowded = R"({"domain_min": [0, 0, 0], "domain_max": [1, 1, 1], "max_particles": 100})";
  EXPECT_NE(message(crowded, inside).find("air.json:/environment/wind/sph/fill:"), std::string::npos)
      << message(crowded, inside);
}

}  // namespace
}  // namespace tendril
