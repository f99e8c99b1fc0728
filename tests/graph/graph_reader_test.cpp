// Graph files are strict like scene files: every mistake is an Error naming the file and the
// JSON pointer of what is wrong, with a message saying what was expected.
#include "graph_test_util.h"

#include "tendril/graph/param.h"

namespace tendril {
namespace {

using graphtest::errorOf;
using graphtest::parse;

// A one-component graph whose component has the given type and params (JSON text).
std::string one(const std::string& type, const std::string& params, const std::string& extra = "") {
  return R"j({"tendril_graph": 1, "root": {"links": ["c"]}, "components": [{"name": "c", "type": ")j" + type +
         R"j(", "params": )j" + params + extra + "}]}";
}

void expectError(const std::string& text, const std::string& location, const std::string& fragment) {
  Error e = errorOf(text);
  EXPECT_EQ(e.source(), "test.json") << e.what();
  EXPECT_EQ(e.location(), location) << e.what();
  EXPECT_NE(e.message().find(fragment), std::string::npos) << e.what();
}

TEST(GraphReader, UnknownKeysWrongTypesAndRangesNameTheirPointer) {
  expectError(one("tree", R"j({"lenght": 2})j"), "/components/0/params/lenght", "did you mean \"length\"");
  expectError(one("tree", R"j({"segments": 0})j"), "/components/0/params/segments", "must be in [1, 10000]");
  expectError(one("tree", R"j({"segments": 2.5})j"), "/components/0/params/segments", "must be an integer");
  expectError(one("tree", R"j({"length": true})j"), "/components/0/params/length", "expected a number, a range");
  expectError(one("tree", R"j({"radius": [0.1]})j"), "/components/0/params/radius", "expected a range [v0, v1]");
  expectError(one("leaf", R"j({"size": [0.1, -1]})j"), "/components/0/params/size/1", "must be in");
  expectError(one("simple", R"j({"shape": "pyramid"})j"), "/components/0/params/shape", "must be one of");
  expectError(one("simple", R"j({"size": [1, 2]})j"), "/components/0/params/size", "expected an array of 3");
  expectError(one("leaf", R"j({"texture": "builtin:oak"})j"), "/components/0/params/texture",
              "unknown built-in texture");
  expectError(one("leaf", R"j({"texture": "nowhere.png"})j"), "/components/0/params/texture", "does not exist");
  expectError(one("hyperpatch", R"j({"degree": 5})j"), "/components/0/params/degree", "[1, 4]");
  expectError(one("hyperpatch", R"j({"degree": 2, "points": [{"index": [0, 3, 0], "offset": [0, 0, 0]}]})j"),
              "/components/0/params/points/0/index/1", "[0, 2]");
  expectError(one("leaf", R"j({"outline": [[0, 0.1], [0, 0.2]]})j"), "/components/0/params/outline/1", "must increase");
  expectError(R"j({"tendril_graph": 1, "components": [{"name": "c", "type": "shrub"}]})j", "/components/0/type",
              "must be one of simple, revo, horn");
  expectError(R"j({"tendril_graph": 1, "components": [{"type": "leaf"}]})j", "/components/0/name", "is required");
  expectError(R"j({"tendril_graph": 1, "components": [{"name": "c", "type": "leaf", "depht": 2}]})j",
              "/components/0/depht", "did you mean \"depth\"");
  expectError(R"j({"tendril_graph": 1, "components": [{"name": "c", "type": "leaf", "exclude": [1, -2]}]})j",
              "/components/0/exclude/1", "iteration number");
  expectError(R"j({"components": []})j", "/tendril_graph", "is required");
  expectError(R"j({"tendril_graph": 2})j", "/tendril_graph", "not supported");
  expectError(R"j({"tendril_graph": 1, "root": {"camera": {"eye": [0, 1, 0], "target": [0, 1, 0]}}})j",
              "/root/camera/eye", "same point");
}

TEST(GraphReader, LinksMustNameComponentsAndCyclesNeedADepth) {
  expectError(R"j({"tendril_graph": 1, "components": [{"name": "stem", "type": "horn", "links": ["leef"]},
                                                       {"name": "leaf", "type": "leaf"}]})j",
              "/components/0/links/0", "no component named \"leef\" (did you mean \"leaf\"?)");
  expectError(R"j({"tendril_graph": 1, "components": [
                   {"name": "stem", "type": "horn", "links": [{"to": "leaf", "type": "twig"}]},
                   {"name": "leaf", "type": "leaf"}]})j",
              "/components/0/links/0/type", "must be one of \"child\", \"branch\", \"leaf\"");
  expectError(R"j({"tendril_graph": 1, "components": [{"name": "a", "type": "leaf"}, {"name": "a", "type": "leaf"}]})j",
              "/components/1/name", "used twice");
  // A cycle without a recursion depth would never end.
  expectError(R"j({"tendril_graph": 1, "root": {"links": ["a"]}, "components": [
                   {"name": "a", "type": "horn", "links": ["b"]},
                   {"name": "b", "type": "hydra", "links": ["a"]}]})j",
              "/components/1/links/0", "the cycle a → b → a has no recursion depth");
  expectError(R"j({"tendril_graph": 1, "components": [{"name": "a", "type": "horn", "links": ["a"]}]})j",
              "/components/0/links/0", "the cycle a → a");
  // With a depth on either component the same graph is fine.
  EXPECT_NO_THROW(parse(R"j({"tendril_graph": 1, "root": {"links": ["a"]}, "components": [
                   {"name": "a", "type": "horn", "links": ["b"]},
                   {"name": "b", "type": "hydra", "depth": 2, "links": ["a"]}]})j"));
  expectError(R"j({"tendril_graph": 1, "root": {"links": [{"to": "a", "type": "branch"}]},
                  "components": [{"name": "a", "type": "leaf"}]})j",
              "/root/links/0", "links of the root are child links");
}

TEST(GraphReader, ExpressionsAreCheckedWhenReadAndWhenEvaluated) {
  // Syntax errors and unknown names are found while reading, at the expression's pointer.
  expectError(one("hydra", R"j({"angle": "30 +"})j"), "/components/0/params/angle", "expression \"30 +\"");
  expectError(one("hydra", R"j({"angle": "30 * foo"})j"), "/components/0/params/angle", "unknown name \"foo\"");
  expectError(one("hydra", R"j({"angle": "bar(3)"})j"), "/components/0/params/angle", "unknown function \"bar\"");
  expectError(one("hydra", R"j({"angle": "30 + s"})j"), "/components/0/params/angle",
              "variable \"s\" is not available here (this parameter offers: i, n, t, depth)");
  expectError(one("hydra", R"j({"angle": "i = 3"})j"), "/components/0/params/angle", "assignments");
  expectError(one("hydra", R"j({"angle": "1, 2"})j"), "/components/0/params/angle", "gives 2 values");
  expectError(one("hydra", R"j({"angle": {"range": [0, 1], "f": "v +"}})j"), "/components/0/params/angle/f",
              "expression");
  expectError(one("hydra", R"j({"angle": {"f": "v"}})j"), "/components/0/params/angle/range", "is required");
  // A constant expression is folded and range-checked at once.
  expectError(one("hydra", R"j({"count": "2 - 5"})j"), "/components/0/params/count", "evaluates to -3");
  // Evaluation errors name the expression, the value and the variables.
  auto g = parse(R"j({"tendril_graph": 1, "root": {"links": ["c"]}, "components": [
                    {"name": "c", "type": "hydra", "params": {"count": 5, "angle": "10 / (i - 2)"}}]})j");
  try {
    graph::expand(g);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "/components/0/params/angle");
    EXPECT_NE(e.message().find("evaluates to inf"), std::string::npos) << e.what();
    EXPECT_NE(e.message().find("i=2"), std::string::npos) << e.what();
  }
  auto range = parse(R"j({"tendril_graph": 1, "root": {"links": ["c"]}, "components": [
                        {"name": "c", "type": "hydra", "params": {"count": "3", "child_scale": "1 - i"}}]})j");
  try {
    graph::expand(range);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "/components/0/params/child_scale");
    EXPECT_EQ(e.message(), "expression \"1 - i\" evaluates to -1, must be in [0, 1000] for i=2, n=3, t=1, depth=0")
        << e.what();
  }
  // Stem profile parameters also name the position along the stem.
  auto profile = parse(R"j({"tendril_graph": 1, "root": {"links": ["c"]}, "components": [
                          {"name": "c", "type": "tree", "params": {"segments": 10, "radius": "0.25 - s"}}]})j");
  try {
    graph::expand(profile);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.location(), "/components/0/params/radius");
    EXPECT_NE(e.message().find("expression \"0.25 - s\" evaluates to -0.05"), std::string::npos) << e.what();
    EXPECT_NE(e.message().find("s=0.3"), std::string::npos) << e.what();
  }
}

TEST(GraphReader, ExpressionFunctionsAndRandomNumbers) {
  graph::Expression e("clamp(sind(90) + mix(0, 10, 0.5) + max(i, 2), 0, 100) + golden - golden + pi - pi", graph::kInstanceVars,
                      "f", "/x");
  graph::EvalVars v;
  v.i = 4;
  EXPECT_DOUBLE_EQ(e.eval(v, nullptr), 1.0 + 5.0 + 4.0);
  // rand() draws from the keyed stream: the same key gives the same numbers, another key others.
  graph::Expression r("rand() + 10 * jitter(1) + 100 * normal()", graph::kInstanceVars, "f", "/r");
  EXPECT_TRUE(r.usesRandom());
  EXPECT_FALSE(r.isConstant());
  RandomKey a{1, 2, 3, 4, 5}, b{1, 2, 3, 4, 6};
  EXPECT_EQ(r.eval(v, &a), r.eval(v, &a));
  EXPECT_NE(r.eval(v, &a), r.eval(v, &b));
  graph::Expression u("rand()", graph::kInstanceVars, "f", "/u");
  for (uint64_t k = 0; k < 200; ++k) {
    RandomKey key{k, 0, 0, 0, 0};
    double x = u.eval(v, &key);
    EXPECT_GE(x, 0.0);
    EXPECT_LT(x, 1.0);
  }
  graph::Expression c("2 * 3 + sqrt(16)", graph::kInstanceVars, "f", "/c");
  EXPECT_TRUE(c.isConstant());
  EXPECT_DOUBLE_EQ(c.constantValue(), 10.0);
}

TEST(GraphReader, OverridesReplaceParametersAndUnknownOnesAreErrors) {
  const char* text = R"j({"tendril_graph": 1, "root": {"links": ["star"]},
    "components": [{"name": "star", "type": "hydra", "params": {"count": 3}, "links": ["leaf"]},
                   {"name": "leaf", "type": "leaf"}]})j";
  graph::Override count{"star/count", Json(7), {"scene.json", "/plants/0/overrides/star~1count"}};
  graph::ITree t = graph::expand(parse(text, {count}));
  EXPECT_EQ(t.countOf("leaf"), 7u);
  graph::Override expression = graph::parseOverride("star/angle=10 + 5 * i", "command line", "--set");
  EXPECT_EQ(expression.value, Json("10 + 5 * i"));
  EXPECT_NO_THROW(graph::expand(parse(text, {expression})));

  auto fails = [&](const graph::Override& o, const std::string& fragment) {
    try {
      parse(text, {o});
      ADD_FAILURE() << "no error for " << o.key;
    } catch (const Error& e) {
      EXPECT_EQ(e.source(), o.location.source);
      EXPECT_EQ(e.location(), o.location.pointer);
      EXPECT_NE(e.message().find(fragment), std::string::npos) << e.what();
    }
  };
  fails({"tree/count", Json(3), {"scene.json", "/plants/0/overrides/tree~1count"}}, "no component named \"tree\"");
  fails({"star/cuont", Json(3), {"scene.json", "/plants/0/overrides/star~1cuont"}},
        "a hydra component has no parameter \"cuont\"");
  fails({"star/count", Json(-1), {"scene.json", "/plants/0/overrides/star~1count"}}, "must be in [0, 1000000]");
  fails({"count", Json(3), {"command line", "--set count"}}, "must name \"component/parameter\"");
  EXPECT_THROW(graph::parseOverride("nothing", "command line", "--set"), Error);
}

}  // namespace
}  // namespace tendril
