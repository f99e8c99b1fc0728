#include "tendril/graph/param.h"

#include "tendril/core/error.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace tendril::graph {

namespace {

std::string rangeText(double min, double max) {
  if (std::isinf(min) && std::isinf(max)) return "finite";
  if (std::isinf(max)) return fmt::format("at least {}", min);
  if (std::isinf(min)) return fmt::format("at most {}", max);
  return fmt::format("in [{}, {}]", min, max);
}

constexpr const char* kScalarForms =
    "a number, a range [v0, v1], an expression string or {\"range\": [v0, v1], \"f\": \"expression\"}";

}  // namespace

uint32_t ParamTable::addLocation(std::string source, std::string pointer) {
  locations.push_back({std::move(source), std::move(pointer)});
  return static_cast<uint32_t>(locations.size() - 1);
}

ParamReader::ParamReader(JsonObject& params, ParamTable& table, const std::string& component,
                         std::map<std::string, const Override*>& overrides)
    : params_(params), table_(table), component_(component), overrides_(overrides) {}

const Json* ParamReader::raw(std::string_view key, Location& where) {
  const Json* fromFile = params_.find(key);
  auto it = overrides_.find(component_ + "/" + std::string(key));
  if (it != overrides_.end()) {
    const Override* o = it->second;
    overrides_.erase(it);  // consumed: what is left over is reported as unknown
    where = o->location;
    return &o->value;
  }
  if (!fromFile) return nullptr;
  where = {params_.source(), params_.pointerTo(key)};
  return fromFile;
}

bool ParamReader::has(std::string_view key) const {
  return params_.has(key) || overrides_.count(component_ + "/" + std::string(key));
}

ParamDef ParamReader::parseScalar(const Json& j, const Location& where, double min, double max, uint32_t vars,
                                  bool integer) {
  ParamDef p;
  p.integer = integer;
  p.min = min;
  p.max = max;
  p.location = table_.addLocation(where.source, where.pointer);
  p.id = table_.nextId++;
  auto fail = [&](const std::string& what) { return Error(where.source, where.pointer, what); };
  auto number = [&](const Json& v, const std::string& pointer) {
    if (!v.is_number()) throw Error(where.source, pointer, fmt::format("expected a number, got {}", describeJson(v)));
    double d = v.get<double>();
    if (!std::isfinite(d) || d < min || d > max)
      throw Error(where.source, pointer, fmt::format("must be {}, got {}", rangeText(min, max), v.dump()));
    if (integer && std::floor(d) != d)
      throw Error(where.source, pointer, fmt::format("must be an integer, got {}", v.dump()));
    return d;
  };
  auto range = [&](const Json& v, const std::string& pointer) {
    if (!v.is_array() || v.size() != 2)
      throw Error(where.source, pointer, fmt::format("expected a range [v0, v1], got {}", describeJson(v)));
    p.v0 = number(v[0], pointer + "/0");
    p.v1 = number(v[1], pointer + "/1");
  };
  auto expression = [&](const Json& v, const std::string& pointer, uint32_t mask) {
    if (!v.is_string())
      throw Error(where.source, pointer, fmt::format("expected an expression string, got {}", describeJson(v)));
    ExpressionDef e{v.get<std::string>(), mask, table_.addLocation(where.source, pointer)};
    // Compiling checks syntax and names now; a constant result is folded.
    Expression compiled(e.text, e.vars, where.source, pointer);
    if (compiled.isConstant()) return std::optional<double>(compiled.constantValue());
    table_.expressions.push_back(std::move(e));
    p.expression = static_cast<int32_t>(table_.expressions.size() - 1);
    return std::optional<double>();
  };

  if (j.is_number()) {
    p.kind = ParamDef::Kind::Constant;
    p.value = number(j, where.pointer);
  } else if (j.is_array()) {
    p.kind = ParamDef::Kind::Range;
    range(j, where.pointer);
  } else if (j.is_string()) {
    std::optional<double> folded = expression(j, where.pointer, vars);
    if (folded) {
      double d = *folded;
      if (d < min || d > max)
        throw fail(fmt::format("expression \"{}\" evaluates to {}, must be {}", j.get<std::string>(), d,
                               rangeText(min, max)));
      p.kind = ParamDef::Kind::Constant;
      p.value = integer ? std::round(d) : d;
    } else {
      p.kind = ParamDef::Kind::Function;
    }
  } else if (j.is_object()) {
    JsonObject o(j, where.source, where.pointer);
    const Json* r = o.find("range");
    const Json* f = o.find("f");
    o.finish();
    if (!r) throw o.error("range", "is required: the range [v0, v1] passed to \"f\"");
    range(*r, o.pointerTo("range"));
    if (!f) {
      p.kind = ParamDef::Kind::Range;
    } else {
      p.kind = ParamDef::Kind::RangeFunction;
      if (std::optional<double> folded = expression(*f, o.pointerTo("f"), vars | kVarV)) {
        p.kind = ParamDef::Kind::Constant;
        p.value = integer ? std::round(*folded) : *folded;
        if (p.value < min || p.value > max)
          throw fail(fmt::format("evaluates to {}, must be {}", p.value, rangeText(min, max)));
      }
    }
  } else {
    throw fail(fmt::format("expected {}, got {}", kScalarForms, describeJson(j)));
  }
  return p;
}

ParamDef ParamReader::scalar(std::string_view key, double fallback, double min, double max, uint32_t vars) {
  Location where;
  const Json* j = raw(key, where);
  if (!j) {
    ParamDef p;
    p.value = fallback;
    p.min = min;
    p.max = max;
    p.location = table_.addLocation(params_.source(), params_.pointerTo(key));
    p.id = table_.nextId++;
    return p;
  }
  return parseScalar(*j, where, min, max, vars, false);
}

ParamDef ParamReader::integer(std::string_view key, int64_t fallback, int64_t min, int64_t max, uint32_t vars) {
  Location where;
  const Json* j = raw(key, where);
  if (!j) {
    ParamDef p;
    p.integer = true;
    p.value = double(fallback);
    p.min = double(min);
    p.max = double(max);
    p.location = table_.addLocation(params_.source(), params_.pointerTo(key));
    p.id = table_.nextId++;
    return p;
  }
  return parseScalar(*j, where, double(min), double(max), vars, true);
}

Vec3Param ParamReader::vec3(std::string_view key, const Vec3& fallback, double min, double max, uint32_t vars) {
  Location where;
  const Json* j = raw(key, where);
  Vec3Param out;
  ParamDef* parts[3] = {&out.x, &out.y, &out.z};
  if (!j) {
    for (int k = 0; k < 3; ++k) {
      parts[k]->value = fallback[k];
      parts[k]->min = min;
      parts[k]->max = max;
      parts[k]->location = table_.addLocation(params_.source(), params_.pointerTo(key));
      parts[k]->id = table_.nextId++;
    }
    return out;
  }
  if (!j->is_array() || j->size() != 3)
    throw Error(where.source, where.pointer,
                fmt::format("expected an array of 3 parameters (numbers, ranges or expressions), got {}",
                            describeJson(*j)));
  for (int k = 0; k < 3; ++k)
    *parts[k] = parseScalar((*j)[size_t(k)], {where.source, where.pointer + "/" + std::to_string(k)}, min, max, vars,
                            false);
  return out;
}

std::string ParamReader::string(std::string_view key, std::string fallback) {
  Location where;
  const Json* j = raw(key, where);
  if (!j) return fallback;
  if (!j->is_string())
    throw Error(where.source, where.pointer, fmt::format("expected a string, got {}", describeJson(*j)));
  return j->get<std::string>();
}

std::string ParamReader::choice(std::string_view key, std::string fallback,
                                std::initializer_list<std::string_view> options) {
  Location where;
  const Json* j = raw(key, where);
  if (!j) return fallback;
  std::string list;
  for (auto o : options) list += (list.empty() ? "\"" : ", \"") + std::string(o) + "\"";
  if (!j->is_string())
    throw Error(where.source, where.pointer, fmt::format("must be one of {}, got {}", list, describeJson(*j)));
  std::string s = j->get<std::string>();
  for (auto o : options)
    if (o == s) return s;
  throw Error(where.source, where.pointer, fmt::format("must be one of {}, got \"{}\"", list, s));
}

bool ParamReader::boolean(std::string_view key, bool fallback) {
  Location where;
  const Json* j = raw(key, where);
  if (!j) return fallback;
  if (!j->is_boolean())
    throw Error(where.source, where.pointer, fmt::format("expected true or false, got {}", describeJson(*j)));
  return j->get<bool>();
}

namespace {

template <int N>
std::vector<Eigen::Matrix<float, N, 1>> readPoints(const Json* j, const Location& where, size_t minCount, double min,
                                                   double max) {
  std::vector<Eigen::Matrix<float, N, 1>> out;
  if (!j) return out;
  if (!j->is_array() || j->size() < minCount)
    throw Error(where.source, where.pointer,
                fmt::format("expected an array of at least {} points [{}], got {}", minCount,
                            N == 2 ? "a, b" : "x, y, z", describeJson(*j)));
  for (size_t k = 0; k < j->size(); ++k) {
    const Json& p = (*j)[k];
    std::string pointer = where.pointer + "/" + std::to_string(k);
    if (!p.is_array() || p.size() != N)
      throw Error(where.source, pointer, fmt::format("expected an array of {} numbers, got {}", N, describeJson(p)));
    Eigen::Matrix<float, N, 1> v;
    for (int c = 0; c < N; ++c) {
      const Json& e = p[size_t(c)];
      if (!e.is_number() || !std::isfinite(e.get<double>()) || e.get<double>() < min || e.get<double>() > max)
        throw Error(where.source, pointer + "/" + std::to_string(c),
                    fmt::format("expected a number {}, got {}", rangeText(min, max), describeJson(e)));
      v[c] = e.get<float>();
    }
    out.push_back(v);
  }
  return out;
}

}  // namespace

std::vector<Vec2> ParamReader::points2(std::string_view key, size_t minCount, double min, double max,
                                       Location* whereOut) {
  Location where;
  const Json* j = raw(key, where);
  if (whereOut) *whereOut = where;
  return readPoints<2>(j, where, minCount, min, max);
}

std::vector<Vec3> ParamReader::points3(std::string_view key, size_t minCount, double min, double max,
                                       Location* whereOut) {
  Location where;
  const Json* j = raw(key, where);
  if (whereOut) *whereOut = where;
  return readPoints<3>(j, where, minCount, min, max);
}

ParamEvaluator::ParamEvaluator(const ParamTable& table) : table_(table) {
  expressions_.reserve(table.expressions.size());
  for (const ExpressionDef& e : table.expressions) {
    const Location& where = table.location(e.location);
    expressions_.push_back(std::make_unique<Expression>(e.text, e.vars, where.source, where.pointer));
  }
}

ParamEvaluator::~ParamEvaluator() = default;

double ParamEvaluator::eval(const ParamDef& p, EvalVars vars, double natural, const RandomKey& key) const {
  double value = p.value;
  switch (p.kind) {
    case ParamDef::Kind::Constant: return p.value;
    case ParamDef::Kind::Range: value = p.v0 + natural * (p.v1 - p.v0); break;
    case ParamDef::Kind::Function:
    case ParamDef::Kind::RangeFunction: {
      if (p.kind == ParamDef::Kind::RangeFunction) vars.v = p.v0 + natural * (p.v1 - p.v0);
      const Expression& e = *expressions_[size_t(p.expression)];
      RandomKey k = key;
      k.purpose = p.id;
      value = e.eval(vars, e.usesRandom() ? &k : nullptr);
      break;
    }
  }
  if (p.integer) value = std::round(value);
  if (!(value >= p.min && value <= p.max)) {
    const Location& where = table_.location(p.location);
    if (p.expression >= 0) {
      const Expression& e = *expressions_[size_t(p.expression)];
      throw Error(where.source, where.pointer,
                  fmt::format("expression \"{}\" evaluates to {}, must be {} for {}", e.text(), value,
                              rangeText(p.min, p.max), e.inputs(vars)));
    }
    throw Error(where.source, where.pointer,
                fmt::format("evaluates to {}, must be {} (i={}, n={}, depth={})", value, rangeText(p.min, p.max),
                            vars.i, vars.n, vars.depth));
  }
  return value;
}

Vec3 ParamEvaluator::eval(const Vec3Param& p, const EvalVars& vars, double natural, const RandomKey& key) const {
  return Vec3(float(eval(p.x, vars, natural, key)), float(eval(p.y, vars, natural, key)),
              float(eval(p.z, vars, natural, key)));
}

}  // namespace tendril::graph
