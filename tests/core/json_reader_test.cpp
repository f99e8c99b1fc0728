#include "tendril/core/json_reader.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace tendril {
namespace {

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(JsonReader, SyntaxErrorNamesLineAndColumn) {
  std::string msg = errorOf([] { parseJson("{\n  \"a\": 1,\n  \"b\": ]\n}", "scene.json"); });
  EXPECT_EQ(msg.rfind("scene.json:3:", 0), 0u) << msg;
}

// A number beyond a double's range is an Error naming the file and where the number is (the
// JSON library throws it as another kind of exception, without a position; found by fuzzing).
TEST(JsonReader, NumberOverflowNamesLineAndColumn) {
  std::string msg = errorOf([] { parseJson("{\n  \"seed\": 1e999\n}", "scene.json"); });
  EXPECT_EQ(msg.rfind("scene.json:2:11: ", 0), 0u) << msg;
  EXPECT_NE(msg.find("1e999"), std::string::npos) << msg;
}

// Coordinates without a range of their own stay within 100 km of the origin: 4e201 would be
// infinite as a float, 1e30 would overflow the simulations' cell indices (found by fuzzing).
TEST(JsonReader, CoordinatesStayWithinTheWorld) {
  const Json j = parseJson(R"({"near": [1e5, -1e5, 0], "far": [0, 4e201, 0], "huge": [1e30, 0, 0]})", "s.json");
  JsonObject o(j, "s.json");
  EXPECT_EQ(o.vec3("near", Vec3::Zero()), Vec3(1e5f, -1e5f, 0.0f));
  EXPECT_EQ(errorOf([&] { o.vec3("far", Vec3::Zero()); }), "s.json:/far/1: must be in [-100000, 100000], got 4e+201");
  EXPECT_EQ(errorOf([&] { o.vec3("huge", Vec3::Zero()); }).rfind("s.json:/huge/0: must be in", 0), 0u);
}

TEST(JsonReader, ReadsValuesWithDefaults) {
  Json j = parseJson(R"({"n": 2.5, "i": 3, "b": true, "s": "x", "v": [1,2,3], "a": 90})", "f");
  JsonObject o(j, "f");
  EXPECT_DOUBLE_EQ(o.number("n", 0), 2.5);
  EXPECT_EQ(o.integer("i", 0, 0, 10), 3);
  EXPECT_TRUE(o.boolean("b", false));
  EXPECT_EQ(o.string("s", ""), "x");
  EXPECT_EQ(o.vec3("v", Vec3::Zero()), Vec3(1, 2, 3));
  EXPECT_NEAR(o.angle("a", 0, 0, 180), kPi / 2, 1e-6);
  EXPECT_EQ(o.number("missing", 7.0), 7.0);
  o.finish();
}

TEST(JsonReader, WrongTypeNamesPointer) {
  Json j = parseJson(R"({"plants": [{"seed": "abc"}]})", "s.json");
  JsonObject root(j, "s.json");
  auto plants = root.objectArray("plants");
  std::string msg = errorOf([&] { plants[0].seed("seed", 0); });
  EXPECT_EQ(msg, "s.json:/plants/0/seed: expected an integer, got string \"abc\"");
  plants[0].finish();
  root.finish();
}

TEST(JsonReader, OutOfRangeNamesPointerAndRange) {
  Json j = parseJson(R"({"p": 1.5, "v": [0, 0, -1]})", "s.json");
  JsonObject o(j, "s.json");
  EXPECT_EQ(errorOf([&] { o.number("p", 0, 0, 1); }), "s.json:/p: must be in [0, 1], got 1.5");
  EXPECT_EQ(errorOf([&] { o.vec3("v", Vec3::Zero(), 0, 10); }), "s.json:/v/2: must be in [0, 10], got -1");
  o.finish();
}

TEST(JsonReader, UnknownKeyIsAnErrorWithSuggestion) {
  Json j = parseJson(R"({"seeed": 3})", "s.json");
  JsonObject o(j, "s.json");
  o.seed("seed", 1);
  EXPECT_EQ(errorOf([&] { o.finish(); }), "s.json:/seeed: unknown key \"seeed\" (did you mean \"seed\"?)");
}

TEST(JsonReader, ChoiceListsOptions) {
  Json j = parseJson(R"({"type": "cube"})", "s.json");
  JsonObject o(j, "s.json");
  EXPECT_EQ(errorOf([&] { o.choice("type", "box", {"box", "sphere"}); }),
            "s.json:/type: must be one of \"box\", \"sphere\", got \"cube\"");
  o.finish();
}

TEST(JsonReader, KeysWithSlashAreEscaped) {
  Json j = parseJson(R"({"a/b": 1})", "s.json");
  JsonObject o(j, "s.json");
  EXPECT_EQ(errorOf([&] { o.finish(); }), "s.json:/a~1b: unknown key \"a/b\"");
}

TEST(JsonReader, MissingFileNamesPath) {
  EXPECT_EQ(errorOf([] { readJsonFile("/nonexistent/x.json"); }),
            "/nonexistent/x.json: cannot open file for reading");
}

}  // namespace
}  // namespace tendril
