#include "tendril/graph/expression.h"

#include "tendril/core/error.h"

#include <fmt/format.h>
#include <muParser.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cctype>
#include <cmath>
#include <optional>
#include <set>
#include <string_view>

namespace tendril::graph {

namespace {

struct VarName {
  uint32_t mask;
  const char* name;
};
constexpr std::array<VarName, 9> kVarNames = {{{kVarI, "i"},
                                                {kVarN, "n"},
                                                {kVarT, "t"},
                                                {kVarDepth, "depth"},
                                                {kVarV, "v"},
                                                {kVarS, "s"},
                                                {kVarXyz, "x"},
                                                {kVarXyz, "y"},
                                                {kVarXyz, "z"}}};

constexpr std::array<const char*, 3> kRandomFunctions = {"rand", "jitter", "normal"};
constexpr double kGoldenRatio = 1.6180339887498948482;
constexpr double kGoldenAngleDegrees = 137.50776405003785;  // 360 (1 - 1/golden ratio)

double fnClamp(double x, double lo, double hi) { return std::min(std::max(x, lo), hi); }
double fnMix(double a, double b, double t) { return a + (b - a) * t; }
double fnSmoothstep(double e0, double e1, double x) {
  double t = e1 == e0 ? (x < e0 ? 0.0 : 1.0) : fnClamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}
double fnStep(double edge, double x) { return x < edge ? 0.0 : 1.0; }
double fnMod(double a, double b) { return a - b * std::floor(a / b); }
double fnFract(double x) { return x - std::floor(x); }
double fnFloor(double x) { return std::floor(x); }
double fnCeil(double x) { return std::ceil(x); }
double fnSind(double d) { return std::sin(d * (M_PI / 180.0)); }
double fnCosd(double d) { return std::cos(d * (M_PI / 180.0)); }
double fnTand(double d) { return std::tan(d * (M_PI / 180.0)); }
double fnPow(double a, double b) { return std::pow(a, b); }

bool isNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool isNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

struct Identifier {
  std::string name;
  bool call = false;  // followed by '('
  size_t position = 0;
};

// The names in an expression, skipping numbers such as 1e-3 (whose 'e' is not a name).
std::vector<Identifier> scanIdentifiers(std::string_view text) {
  std::vector<Identifier> out;
  size_t k = 0;
  while (k < text.size()) {
    char c = text[k];
    if (std::isdigit(static_cast<unsigned char>(c)) ||
        (c == '.' && k + 1 < text.size() && std::isdigit(static_cast<unsigned char>(text[k + 1])))) {
      while (k < text.size() && (std::isdigit(static_cast<unsigned char>(text[k])) || text[k] == '.')) ++k;
      if (k < text.size() && (text[k] == 'e' || text[k] == 'E')) {
        size_t e = k + 1;
        if (e < text.size() && (text[e] == '+' || text[e] == '-')) ++e;
        if (e < text.size() && std::isdigit(static_cast<unsigned char>(text[e]))) {
          k = e;
          while (k < text.size() && std::isdigit(static_cast<unsigned char>(text[k]))) ++k;
        }
      }
      continue;
    }
    if (isNameStart(c)) {
      size_t start = k;
      while (k < text.size() && isNameChar(text[k])) ++k;
      size_t after = k;
      while (after < text.size() && std::isspace(static_cast<unsigned char>(text[after]))) ++after;
      out.push_back({std::string(text.substr(start, k - start)), after < text.size() && text[after] == '(', start});
      continue;
    }
    ++k;
  }
  return out;
}

// '=' that is not part of ==, <=, >= or !=.
bool hasAssignment(std::string_view text) {
  for (size_t k = 0; k < text.size(); ++k) {
    if (text[k] != '=') continue;
    char prev = k > 0 ? text[k - 1] : ' ';
    char next = k + 1 < text.size() ? text[k + 1] : ' ';
    if (next == '=') {
      ++k;
      continue;
    }
    if (prev == '<' || prev == '>' || prev == '!' || prev == '=') continue;
    return true;
  }
  return false;
}

}  // namespace

std::string variableNames(uint32_t mask) {
  std::string s;
  for (const VarName& v : kVarNames)
    if (mask & v.mask) s += (s.empty() ? "" : ", ") + std::string(v.name);
  return s.empty() ? std::string("none") : s;
}

struct Expression::State {
  EvalVars vars;
  std::optional<Rng> rng;
  static double rand(void* self) {
    auto* s = static_cast<State*>(self);
    assert(s->rng);
    return s->rng->uniform();
  }
  static double jitter(void* self, double a) { return a * (2.0 * rand(self) - 1.0); }
  static double normal(void* self) {
    auto* s = static_cast<State*>(self);
    assert(s->rng);
    return s->rng->normal();
  }
};

Expression::Expression(const std::string& text, uint32_t vars, std::string source, std::string pointer)
    : text_(text),
      source_(std::move(source)),
      pointer_(std::move(pointer)),
      vars_(vars),
      state_(std::make_unique<State>()),
      parser_(std::make_unique<mu::Parser>()) {
  auto fail = [&](const std::string& what) {
    return Error(source_, pointer_, fmt::format("expression \"{}\": {}", text_, what));
  };
  if (text_.find_first_not_of(" \t\r\n") == std::string::npos) throw fail("is empty");
  if (hasAssignment(text_)) throw fail("assignments (=) are not allowed; use == to compare");

  mu::Parser& p = *parser_;
  try {
    p.DefineConst("pi", M_PI);
    p.DefineConst("phi", kGoldenRatio);
    p.DefineConst("golden", kGoldenAngleDegrees);
    p.DefineFun("clamp", fnClamp);
    p.DefineFun("mix", fnMix);
    p.DefineFun("smoothstep", fnSmoothstep);
    p.DefineFun("step", fnStep);
    p.DefineFun("mod", fnMod);
    p.DefineFun("fract", fnFract);
    p.DefineFun("floor", fnFloor);
    p.DefineFun("ceil", fnCeil);
    p.DefineFun("sind", fnSind);
    p.DefineFun("cosd", fnCosd);
    p.DefineFun("tand", fnTand);
    p.DefineFun("pow", fnPow);
    // Random functions must not be folded into constants by muParser's optimiser.
    p.DefineFunUserData("rand", &State::rand, state_.get(), false);
    p.DefineFunUserData("jitter", &State::jitter, state_.get(), false);
    p.DefineFunUserData("normal", &State::normal, state_.get(), false);
    double* slots[] = {&state_->vars.i, &state_->vars.n, &state_->vars.t, &state_->vars.depth, &state_->vars.v,
                       &state_->vars.s, &state_->vars.x, &state_->vars.y, &state_->vars.z};
    for (size_t k = 0; k < kVarNames.size(); ++k)
      if (vars & kVarNames[k].mask) p.DefineVar(kVarNames[k].name, slots[k]);
  } catch (const mu::Parser::exception_type& e) {
    throw fail(e.GetMsg());
  }

  // Check every name first: muParser's "unexpected token" does not say what is available.
  const auto& functions = p.GetFunDef();
  const auto& constants = p.GetConst();
  bool usesVariable = false;
  for (const Identifier& id : scanIdentifiers(text_)) {
    if (id.call) {
      if (!functions.count(id.name)) {
        std::string list;
        for (const auto& [name, cb] : functions) list += (list.empty() ? "" : ", ") + name;
        throw fail(fmt::format("unknown function \"{}\" (functions: {})", id.name, list));
      }
      if (std::find(kRandomFunctions.begin(), kRandomFunctions.end(), id.name) != kRandomFunctions.end())
        usesRandom_ = true;
      continue;
    }
    if (constants.count(id.name)) continue;
    auto known = std::find_if(kVarNames.begin(), kVarNames.end(), [&](const VarName& v) { return id.name == v.name; });
    if (known != kVarNames.end()) {
      if (!(vars & known->mask))
        throw fail(fmt::format("variable \"{}\" is not available here (this parameter offers: {})", id.name,
                               variableNames(vars)));
      usesVariable = true;
      continue;
    }
    throw fail(fmt::format("unknown name \"{}\" (variables here: {}; constants: pi, phi, golden, _pi, _e)", id.name,
                           variableNames(vars)));
  }

  try {
    p.SetExpr(text_);
    // Parse now (muParser parses on first use) with neutral inputs so that syntax errors
    // surface while the file is read.
    RandomKey probe;
    state_->rng.emplace(probe);
    int results = 0;
    double* values = p.Eval(results);
    if (results != 1) throw fail(fmt::format("gives {} values; write a single expression", results));
    constant_ = !usesVariable && !usesRandom_;
    if (constant_) {
      constantValue_ = values[0];
      if (!std::isfinite(constantValue_)) throw fail(fmt::format("evaluates to {}", constantValue_));
    }
  } catch (const mu::Parser::exception_type& e) {
    throw fail(e.GetMsg());
  }
}

Expression::~Expression() = default;

double Expression::eval(const EvalVars& vars, const RandomKey* key) const {
  if (constant_) return constantValue_;
  state_->vars = vars;
  if (usesRandom_) {
    assert(key);
    state_->rng.emplace(*key);
  }
  double value;
  try {
    value = parser_->Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw Error(source_, pointer_, fmt::format("expression \"{}\": {}", text_, e.GetMsg()));
  }
  if (!std::isfinite(value))
    throw Error(source_, pointer_,
                fmt::format("expression \"{}\" evaluates to {} (division by zero or a function outside its domain?) for "
                            "{}",
                            text_, value, inputs(vars)));
  return value;
}

std::string Expression::inputs(const EvalVars& vars) const {
  std::string out;
  const double values[] = {vars.i, vars.n, vars.t, vars.depth, vars.v, vars.s, vars.x, vars.y, vars.z};
  for (size_t k = 0; k < kVarNames.size(); ++k)
    if (vars_ & kVarNames[k].mask) out += fmt::format("{}{}={}", out.empty() ? "" : ", ", kVarNames[k].name, values[k]);
  return out.empty() ? std::string("no inputs") : out;
}

}  // namespace tendril::graph
