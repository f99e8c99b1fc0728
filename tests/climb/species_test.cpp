#include "tendril/climb/climb_model.h"
#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace tendril::climb {
namespace {

void expectSameSpecies(const ClimbSpecies& a, const ClimbSpecies& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.segmentLength, b.segmentLength);
  EXPECT_EQ(a.radius, b.radius);
  EXPECT_EQ(a.leafSize, b.leafSize);
  EXPECT_EQ(a.decreaseRadius, b.decreaseRadius);
  EXPECT_EQ(a.decreaseLength, b.decreaseLength);
  EXPECT_EQ(a.decreaseLeafSize, b.decreaseLeafSize);
  EXPECT_EQ(a.minLength, b.minLength);
  EXPECT_EQ(a.minRadius, b.minRadius);
  EXPECT_EQ(a.branchFalloff, b.branchFalloff);
  EXPECT_EQ(a.pipeModel, b.pipeModel);
  EXPECT_EQ(a.gravity, b.gravity);
  EXPECT_EQ(a.light, b.light);
  EXPECT_EQ(a.lightAmbient, b.lightAmbient);
  EXPECT_EQ(a.randomness, b.randomness);
  EXPECT_EQ(a.adhesion, b.adhesion);
  EXPECT_EQ(a.up, b.up);
  EXPECT_EQ(a.userDirection, b.userDirection);
  EXPECT_EQ(a.userDirectionStrength, b.userDirectionStrength);
  EXPECT_EQ(a.windStrength, b.windStrength);
  EXPECT_EQ(a.attraction, b.attraction);
  EXPECT_EQ(a.adhesionDistance, b.adhesionDistance);
  EXPECT_FLOAT_EQ(a.releaseAngle, b.releaseAngle);
  EXPECT_EQ(a.surfaceOffset, b.surfaceOffset);
  EXPECT_EQ(a.surfaceHold, b.surfaceHold);
  EXPECT_EQ(a.maxUnsupported, b.maxUnsupported);
  EXPECT_FLOAT_EQ(a.branchAngleMin, b.branchAngleMin);
  EXPECT_FLOAT_EQ(a.branchAngleMax, b.branchAngleMax);
  EXPECT_EQ(a.crowdingRadius, b.crowdingRadius);
  EXPECT_EQ(a.crowdingLimit, b.crowdingLimit);
  ASSERT_EQ(a.leafShapes.size(), b.leafShapes.size());
  for (size_t i = 0; i < a.leafShapes.size(); ++i) {
    EXPECT_EQ(a.leafShapes[i].texture, b.leafShapes[i].texture);
    EXPECT_EQ(a.leafShapes[i].aspect, b.leafShapes[i].aspect);
  }
  EXPECT_FLOAT_EQ(a.leafSpread, b.leafSpread);
  EXPECT_FLOAT_EQ(a.leafJitter, b.leafJitter);
  EXPECT_EQ(a.leafPetiole, b.leafPetiole);
  EXPECT_EQ(a.leafLift, b.leafLift);
  EXPECT_EQ(a.leafThickness, b.leafThickness);
  EXPECT_EQ(a.bark.texture, b.bark.texture);
  EXPECT_EQ(a.bark.color, b.bark.color);
  ASSERT_EQ(a.rules.size(), b.rules.size());
  for (size_t i = 0; i < a.rules.size(); ++i) {
    EXPECT_EQ(a.rules[i].kind, b.rules[i].kind);
    EXPECT_EQ(a.rules[i].every, b.rules[i].every);
    EXPECT_EQ(a.rules[i].probability, b.rules[i].probability);
  }
  EXPECT_EQ(a.maxSegments, b.maxSegments);
}

TEST(ClimbSpecies, IvyPresetFileIsTheCodeDefault) {
  // examples/species/japanese-ivy.json documents every value; it must not drift from the code.
  ClimbSpecies fromFile = loadSpecies("japanese-ivy", "");
  ClimbSpecies defaults;
  defaults.description = fromFile.description;
  expectSameSpecies(fromFile, defaults);
}

TEST(ClimbSpecies, BuiltinsIncludeAContrastingClimber) {
  std::vector<std::string> names = builtinSpeciesNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "japanese-ivy"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "clematis"), names.end());
  ClimbSpecies c = loadSpecies("clematis", "");
  ClimbSpecies ivy = loadSpecies("japanese-ivy", "");
  EXPECT_GT(c.segmentLength, ivy.segmentLength);  // longer internodes
  EXPECT_LT(c.radius, ivy.radius);                // thinner stems
  EXPECT_EQ(c.leafShapes[0].texture, "builtin:heart-0");
}

TEST(ClimbSpecies, OverridesChangeOnlyTheirKeys) {
  Json j = parseJson(R"({"branch_angle": [30, 33], "tropisms": {"light": 0.5}, "decrease": {"length": 0.9}})", "o");
  JsonObject o(j, "o");
  ClimbSpecies s;
  readClimbSpecies(o, s, "");
  o.finish();
  ClimbSpecies d;
  EXPECT_FLOAT_EQ(s.branchAngleMin, radians(30));
  EXPECT_FLOAT_EQ(s.branchAngleMax, radians(33));
  EXPECT_EQ(s.light, 0.5f);
  EXPECT_EQ(s.decreaseLength, 0.9f);
  EXPECT_EQ(s.decreaseRadius, d.decreaseRadius);
  EXPECT_EQ(s.gravity, d.gravity);
  EXPECT_EQ(s.rules.size(), d.rules.size());
}

TEST(ClimbSpecies, BadValuesAreErrorsWithPointers) {
  auto error = [](const char* json) -> std::string {
    Json j = parseJson(json, "s.json");
    JsonObject o(j, "s.json");
    ClimbSpecies s;
    try {
      readClimbSpecies(o, s, "");
      o.finish();
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(error(R"({"branch_angle": [40, 30]})"), "s.json:/branch_angle: must satisfy 0 <= min <= max <= 90 (degrees)");
  EXPECT_EQ(error(R"({"rules": [{"rule": "sprout"}]})"),
            "s.json:/rules/0/rule: must be one of \"tropism\", \"decrease\", \"collision_avoidance\", \"die\", "
            "\"place_leaf\", \"branch\", got \"sprout\"");
  EXPECT_EQ(error(R"({"rules": [{"rule": "collision_avoidance", "every": 2}]})").rfind("s.json:/rules/0: collision", 0), 0u);
  EXPECT_EQ(error(R"({"leaf": {"textures": []}})"),
            "s.json:/leaf/textures: expected a non-empty array of texture names or image paths");
  EXPECT_EQ(error(R"({"tropisms": {"ligth": 1}})"), "s.json:/tropisms/ligth: unknown key \"ligth\" (did you mean \"light\"?)");
  EXPECT_EQ(error(R"({"tropisms": {"up": -0.1}})"), "s.json:/tropisms/up: must be in [0, 3], got -0.1");
}

}  // namespace
}  // namespace tendril::climb
