// Component parameters: a constant, a range, a function, or a range passed through a function.
//
// seed 004: "the prototype of a multiplying component stores several parameters (for example,
// the size of its children) as ranges. ... If the parameter range is [v0, v1], the value of the
// i-th child out of n is v_i = v0 + i(v1 − v0)/(n − 1). Before the system uses this parameter
// value, it applies an arbitrary function that the user specifies."
//
// In a file a scalar parameter is one of
//   1.5                               a constant
//   [0.5, 1.0]                        a range, interpolated by the parameter's natural variable
//   "30 + 10 * sin(i)"                a function (muParser, see expression.h)
//   {"range": [0.5, 1], "f": "v * (0.9 + 0.2 * rand())"}   a range passed through a function
// A vector parameter is an array of three scalar parameters. The natural variable of a range
// is the instance's t = i / (n − 1) for most parameters and the position along the stem for the
// stem profile parameters; docs/graph-format.md lists it per parameter.
#pragma once

#include "tendril/core/json_reader.h"
#include "tendril/graph/expression.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace tendril::graph {

// Where a value came from, for error messages (overrides come from scenes or the CLI).
struct Location {
  std::string source;
  std::string pointer;
};

// An expression as written in a file; every expansion compiles its own copy.
struct ExpressionDef {
  std::string text;
  uint32_t vars = 0;
  uint32_t location = 0;  // index into ParamTable::locations
};

struct ParamDef {
  enum class Kind : uint8_t { Constant, Range, Function, RangeFunction };
  Kind kind = Kind::Constant;
  bool integer = false;
  double value = 0;            // Constant
  double v0 = 0, v1 = 0;       // Range, RangeFunction
  int32_t expression = -1;     // Function, RangeFunction: index into ParamTable::expressions
  double min = -JsonObject::kInf, max = JsonObject::kInf;
  uint32_t location = 0;       // index into ParamTable::locations
  uint32_t id = 0;             // distinct per parameter of the graph: keys its random stream

  bool isConstant() const { return kind == Kind::Constant; }
  // The value when it does not vary (Constant), else `fallback`.
  double constantOr(double fallback) const { return kind == Kind::Constant ? value : fallback; }
};

struct Vec3Param {
  ParamDef x, y, z;
  bool isConstant() const { return x.isConstant() && y.isConstant() && z.isConstant(); }
  Vec3 constantValue() const { return Vec3(float(x.value), float(y.value), float(z.value)); }
};

// A parameter value given from outside the graph file: "component/parameter" → JSON value.
struct Override {
  std::string key;  // "trunk/branches"
  Json value;
  Location location;  // where the override was written (scene file + pointer, or the command line)
};

// Everything the parameters of one graph refer to.
struct ParamTable {
  std::vector<Location> locations;
  std::vector<ExpressionDef> expressions;
  uint32_t nextId = 1;

  uint32_t addLocation(std::string source, std::string pointer);
  const Location& location(uint32_t index) const { return locations[index]; }
};

// Reads the parameters of one component, applying overrides. Every parameter the component
// type knows is read through it, so finish() can report unknown keys and unused overrides.
class ParamReader {
 public:
  ParamReader(JsonObject& params, ParamTable& table, const std::string& component,
              std::map<std::string, const Override*>& overrides);

  // `vars`: the variables a function may use; kVarV is added for range + function.
  ParamDef scalar(std::string_view key, double fallback, double min, double max, uint32_t vars = kInstanceVars);
  ParamDef integer(std::string_view key, int64_t fallback, int64_t min, int64_t max, uint32_t vars = kInstanceVars);
  // An angle in degrees (values stay in degrees; callers convert).
  ParamDef degrees(std::string_view key, double fallback, double min, double max, uint32_t vars = kInstanceVars) {
    return scalar(key, fallback, min, max, vars);
  }
  Vec3Param vec3(std::string_view key, const Vec3& fallback, double min, double max, uint32_t vars = kInstanceVars);

  // Plain values (no functions): strings, booleans and point lists.
  std::string choice(std::string_view key, std::string fallback, std::initializer_list<std::string_view> options);
  std::string string(std::string_view key, std::string fallback);
  bool boolean(std::string_view key, bool fallback);
  bool has(std::string_view key) const;
  // An array of [a, b] pairs (at least `minCount`), each number within [min, max].
  // `where` (optional) receives the location of the list.
  std::vector<Vec2> points2(std::string_view key, size_t minCount, double min, double max, Location* where = nullptr);
  std::vector<Vec3> points3(std::string_view key, size_t minCount, double min, double max, Location* where = nullptr);
  // The raw JSON of a key (override or file) with its location, or nullptr; marks it read.
  const Json* raw(std::string_view key, Location& where);

 private:
  ParamDef parseScalar(const Json& value, const Location& where, double min, double max, uint32_t vars, bool integer);
  JsonObject& params_;
  ParamTable& table_;
  std::string component_;
  std::map<std::string, const Override*>& overrides_;
};

// Evaluates parameters during one expansion; owns that expansion's compiled expressions.
class ParamEvaluator {
 public:
  explicit ParamEvaluator(const ParamTable& table);
  ~ParamEvaluator();

  // `natural`: the range's interpolation variable in [0, 1]. `key`: the random stream of this
  // evaluation (its purpose is replaced by the parameter's id). Values outside the parameter's
  // range, non-integers for integer parameters and non-finite results are Errors naming the
  // parameter's file and pointer.
  double eval(const ParamDef& p, EvalVars vars, double natural, const RandomKey& key) const;
  Vec3 eval(const Vec3Param& p, const EvalVars& vars, double natural, const RandomKey& key) const;
  const Expression& expression(int32_t index) const { return *expressions_[size_t(index)]; }

 private:
  const ParamTable& table_;
  std::vector<std::unique_ptr<Expression>> expressions_;
};

}  // namespace tendril::graph
