#include "tendril/lsystem/compiler.h"

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/core/log.h"
#include "tendril/io/texture.h"
#include "tendril/lsystem/parser.h"
#include "tendril/lsystem/rule_choice.h"
#include "tendril/lsystem/turtle.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace tendril::lsystem {

namespace {

using syntax::Expr;
using syntax::Stmt;

constexpr int kMaxDerivationLength = 10'000'000;
constexpr int kMaxDepthLimit = 1000;
constexpr size_t kMaxProgram = 50'000'000;  // instructions (an axiom of millions of modules)
constexpr uint16_t kMaxStackDepth = 512;

struct Predefined {
  const char* name;
  double value;
};
const Predefined kConstants[] = {
    {"PI", 3.14159265358979323846}, {"SURFACE", double(QueryKind::Surface)}, {"HIT", double(QueryKind::Hit)},
    {"LIGHT", double(QueryKind::Light)}, {"ATTRACT", double(QueryKind::Attract)},
    {"FACING", double(QueryKind::Facing)},
};

struct TurtleModule {
  const char* name;
  TurtleOp op;
  uint8_t minArity, maxArity;
};
const TurtleModule kTurtleModules[] = {
    {"F", TurtleOp::Forward, 0, 1},        {"f", TurtleOp::Move, 0, 1},
    {"+", TurtleOp::TurnLeft, 0, 1},       {"-", TurtleOp::TurnRight, 0, 1},
    {"&", TurtleOp::PitchDown, 0, 1},      {"^", TurtleOp::PitchUp, 0, 1},
    {"\\", TurtleOp::RollLeft, 0, 1},      {"/", TurtleOp::RollRight, 0, 1},
    {"|", TurtleOp::TurnAround, 0, 0},     {"$", TurtleOp::RollHorizontal, 0, 0},
    {"[", TurtleOp::Push, 0, 0},           {"]", TurtleOp::Pop, 0, 0},
    {"!", TurtleOp::Width, 0, 1},          {"'", TurtleOp::Color, 0, 1},
    {"{", TurtleOp::PolygonBegin, 0, 0},   {"}", TurtleOp::PolygonEnd, 0, 0},
    {".", TurtleOp::Vertex, 0, 0},         {"%", TurtleOp::Cut, 0, 0},
    {"@R", TurtleOp::SetHeading, 3, 6},    {"@M", TurtleOp::MoveTo, 3, 3},
    {"@Tv", TurtleOp::TropismVector, 3, 3}, {"@Te", TurtleOp::Elasticity, 1, 1},
    {"@O", TurtleOp::Sphere, 0, 1},        {"@Climb", TurtleOp::Climbing, 1, 1},
    {"~leaf", TurtleOp::Leaf, 0, 3},       {"?P", TurtleOp::QueryPosition, 3, 3},
    {"?H", TurtleOp::QueryHeading, 3, 3},  {"?U", TurtleOp::QueryUp, 3, 3},
    {"?L", TurtleOp::QueryLeft, 3, 3},     {"?E", TurtleOp::QueryEnvironment, 1, 7},
};

const TurtleModule* findTurtleModule(std::string_view name) {
  for (const TurtleModule& t : kTurtleModules)
    if (name == t.name) return &t;
  return nullptr;
}

std::string suggestion(const std::string& name, const std::vector<std::string>& candidates) {
  std::string best;
  size_t bestDistance = std::max<size_t>(2, name.size() / 3 + 1);
  for (const std::string& c : candidates) {
    size_t d = editDistance(name, c);
    if (d < bestDistance) {
      bestDistance = d;
      best = c;
    }
  }
  return best.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", best);
}

// Writes emitted modules into a string (axiom, surfaces); parameters must be finite.
class StringSink final : public EmitSink {
 public:
  StringSink(LString& out, const Grammar& g) : out_(out), g_(g) {}
  void emit(ModuleId id, const double* p, uint32_t n, uint32_t loc) override {
    float f[256];
    for (uint32_t i = 0; i < n; ++i) {
      f[i] = float(p[i]);
      if (!std::isfinite(f[i]))
        throw EvalFailure{loc, fmt::format("parameter {} of {} is not a finite number ({:g})", i + 1,
                                           g_.modules[id].name, p[i])};
    }
    out_.push(id, f, n, 0);
  }

 private:
  LString& out_;
  const Grammar& g_;
};

class Compiler {
 public:
  Compiler(const syntax::Grammar& ast, const std::string& source, const CompileOptions& options)
      : ast_(ast), options_(options) {
    g_ = std::make_shared<Grammar>();
    g_->source = source;
    g_->dir = options.dir;
    g_->locations.push_back({0, 0});
  }

  std::shared_ptr<const Grammar> compile() {
    Grammar& g = *g_;
    g.name = ast_.name;
    defines();
    settings();
    modules();
    globals();
    // Blocks, axiom, productions.
    g.start = block(ast_.start, "Start");
    g.startEach = block(ast_.startEach, "StartEach");
    g.endEach = block(ast_.endEach, "EndEach");
    g.end = block(ast_.end, "End");
    if (!ast_.axiom) throw Error(g.source, "", "the grammar has no axiom: (the string derivation starts from)");
    {
      Scope scope;
      scope.kind = ScopeKind::Axiom;
      g.axiom = successor(ast_.axiom->value, scope, "axiom");
      g.producesCut |= emitsCut(ast_.axiom->value);
    }
    productions();
    contextSets();
    surfaces();
    g.hasQueries = false;
    for (const ModuleInfo& m : g.modules) g.hasQueries |= isQuery(m.op);
    std::vector<std::vector<ModuleId>> idsByName(g.names.size());
    for (ModuleId id = 0; id < g.modules.size(); ++id) idsByName[g.modules[id].nameIndex].push_back(id);
    for (int s = 0; s < kSectionCount; ++s) {
      g.candidates[s].assign(g.modules.size(), {});
      for (uint32_t i = 0; i < g.productions.size(); ++i) {
        const Production& p = g.productions[i];
        if (int(p.section) != s) continue;
        for (ModuleId id : idsByName[p.predName])
          if (p.predArity < 0 || p.predArity == g.modules[id].arity) g.candidates[s][id].push_back(i);
      }
      g.maxGroup = std::max<uint32_t>(g.maxGroup, uint32_t(largestGroup(g, Section(s))));
    }
    return g_;
  }

 private:
  // --- errors and locations ----------------------------------------------------------

  [[noreturn]] void error(SourcePos pos, const std::string& message) const {
    throw Error(g_->source, pos.line ? fmt::format("{}:{}", pos.line, pos.col) : "", message);
  }
  uint32_t loc(SourcePos pos) {
    g_->locations.push_back(pos);
    return uint32_t(g_->locations.size() - 1);
  }

  // --- constants ---------------------------------------------------------------------

  // The value of an expression made of numbers, defines, predefined constants and pure
  // functions; nullopt when it uses anything else.
  std::optional<double> constant(const Expr& e) {
    switch (e.kind) {
      case Expr::Kind::Number: return e.value;
      case Expr::Kind::Name: {
        if (scopeHas(e.name)) return std::nullopt;
        for (auto& [n, v] : defineValues_)
          if (n == e.name) return v;
        for (const Predefined& c : kConstants)
          if (e.name == c.name) return c.value;
        return std::nullopt;
      }
      case Expr::Kind::Unary: {
        auto a = constant(*e.args[0]);
        if (!a) return std::nullopt;
        return e.op == '-' ? -*a : (*a == 0.0 ? 1.0 : 0.0);
      }
      case Expr::Kind::Binary: {
        auto a = constant(*e.args[0]);
        auto b = constant(*e.args[1]);
        if (!a || !b) return std::nullopt;
        return foldBinary(e, *a, *b);
      }
      case Expr::Kind::And:
      case Expr::Kind::Or: {
        auto a = constant(*e.args[0]);
        auto b = constant(*e.args[1]);
        if (!a || !b) return std::nullopt;
        bool r = e.kind == Expr::Kind::And ? (*a != 0.0 && *b != 0.0) : (*a != 0.0 || *b != 0.0);
        return r ? 1.0 : 0.0;
      }
      case Expr::Kind::Ternary: {
        auto c = constant(*e.args[0]);
        if (!c) return std::nullopt;
        return constant(*e.args[*c != 0.0 ? 1 : 2]);
      }
      case Expr::Kind::Call: {
        Fn f = function(e);
        if (fnInfo(f).random) return std::nullopt;
        double args[8];
        for (size_t i = 0; i < e.args.size(); ++i) {
          auto a = constant(*e.args[i]);
          if (!a) return std::nullopt;
          args[i] = *a;
        }
        try {
          return callFunction(f, args, int(e.args.size()), nullptr, 0);
        } catch (const EvalFailure& f) {
          error(e.pos, f.message);
        }
      }
    }
    return std::nullopt;
  }

  double foldBinary(const Expr& e, double a, double b) {
    switch (e.op) {
      case '+': return a + b;
      case '-': return a - b;
      case '*': return a * b;
      case '/':
        if (b == 0.0) error(e.pos, "division by zero");
        return a / b;
      case '%':
        if (b == 0.0) error(e.pos, "modulo by zero");
        return std::fmod(a, b);
      case '^': {
        double r = std::pow(a, b);
        if (!std::isfinite(r)) error(e.pos, fmt::format("{:g} ^ {:g} is not a finite number", a, b));
        return r;
      }
      case '<': return a < b;
      case 'L': return a <= b;
      case '>': return a > b;
      case 'G': return a >= b;
      case '=': return a == b;
      case 'N': return a != b;
    }
    error(e.pos, "unknown operator");
  }

  double requireConstant(const Expr& e, const char* what) {
    auto v = constant(e);
    if (!v) {
      checkNames(e);  // an unknown name is the better message
      error(e.pos, fmt::format("{} must be a constant (numbers, define: constants and functions of them)", what));
    }
    if (!std::isfinite(*v)) error(e.pos, fmt::format("{} is not a finite number", what));
    return *v;
  }

  double requireRange(const syntax::Setting<syntax::ExprPtr>& s, const char* what, double lo, double hi) {
    double v = requireConstant(*s.value, what);
    if (v < lo || v > hi) error(s.value->pos, fmt::format("{} must lie in [{:g}, {:g}], got {:g}", what, lo, hi, v));
    return v;
  }

  int64_t requireInteger(const syntax::Setting<syntax::ExprPtr>& s, const char* what, double lo, double hi) {
    double v = requireRange(s, what, lo, hi);
    if (v != std::floor(v)) error(s.value->pos, fmt::format("{} must be a whole number, got {:g}", what, v));
    return int64_t(v);
  }

  // Reports the first unknown name or function in an expression.
  void checkNames(const Expr& e) {
    if (e.kind == Expr::Kind::Name && !constant(e) && !scopeHas(e.name) && globalIndex(e.name) < 0)
      unknownName(e);
    if (e.kind == Expr::Kind::Call) function(e);
    for (const auto& a : e.args) checkNames(*a);
  }

  [[noreturn]] void unknownName(const Expr& e) {
    std::vector<std::string> names;
    for (auto& [n, v] : defineValues_) names.push_back(n);
    for (const std::string& n : g_->globalNames) names.push_back(n);
    for (const Predefined& c : kConstants) names.push_back(c.name);
    if (scope_)
      for (auto& [n, s] : scope_->slots) names.push_back(n);
    error(e.pos, fmt::format("unknown name \"{}\"{}", e.name, suggestion(e.name, names)));
  }

  Fn function(const Expr& e) {
    for (int i = 0; i < int(Fn::Count); ++i) {
      const FnInfo& f = fnInfo(Fn(i));
      if (e.name != f.name) continue;
      if (e.args.size() < f.minArgs || e.args.size() > f.maxArgs) {
        std::string count = f.minArgs == f.maxArgs ? fmt::format("{}", f.minArgs)
                                                   : fmt::format("{} to {}", f.minArgs, f.maxArgs);
        error(e.pos, fmt::format("{}() takes {} argument{}, got {}", f.name, count, f.maxArgs == 1 ? "" : "s",
                                 e.args.size()));
      }
      return Fn(i);
    }
    std::vector<std::string> names;
    for (int i = 0; i < int(Fn::Count); ++i) names.push_back(fnInfo(Fn(i)).name);
    error(e.pos, fmt::format("unknown function {}(){}", e.name, suggestion(e.name, names)));
  }

  void defines() {
    std::set<std::string> overridden;
    for (const syntax::Assignment& a : ast_.defines) {
      for (const Predefined& c : kConstants)
        if (a.name == c.name) error(a.pos, fmt::format("{} is a predefined constant", a.name));
      for (auto& [n, v] : defineValues_)
        if (n == a.name) error(a.pos, fmt::format("\"{}\" is defined twice", a.name));
      double v = 0.0;
      auto o = std::find_if(options_.defines.begin(), options_.defines.end(),
                            [&](const auto& d) { return d.first == a.name; });
      if (o != options_.defines.end()) {
        v = o->second;
        overridden.insert(a.name);
      } else {
        v = requireConstant(*a.value, "a define: value");
      }
      defineValues_.emplace_back(a.name, v);
    }
    for (const auto& [name, value] : options_.defines) {
      if (overridden.count(name)) continue;
      std::vector<std::string> names;
      for (auto& [n, v] : defineValues_) names.push_back(n);
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
      throw Error(g_->source, "",
                  fmt::format("cannot set \"{}\": the grammar defines no such constant{} (its define: constants: {})",
                              name, suggestion(name, names), list.empty() ? "none" : list));
    }
    g_->defines = defineValues_;
  }

  void settings() {
    Grammar& g = *g_;
    TurtleSettings& t = g.turtle;
    if (ast_.seed) g.seed = uint64_t(requireInteger(*ast_.seed, "seed", 0, 9007199254740992.0));
    if (ast_.derivationLength)
      g.derivationLength = int(requireInteger(*ast_.derivationLength, "derivation length", 0, kMaxDerivationLength));
    if (ast_.maxLength) {
      g.limits.maxModules = size_t(requireInteger(*ast_.maxLength, "max length", 1, 1e9));
      g.limits.maxParams = kParamsPerModule * g.limits.maxModules;
    }
    if (ast_.angle) t.angle = radians(float(requireRange(*ast_.angle, "angle", -1e6, 1e6)));
    if (ast_.step) t.step = float(requireRange(*ast_.step, "step", 0.0, 1e6));
    if (ast_.width) t.width = float(requireRange(*ast_.width, "width", 1e-9, 1e6));
    if (ast_.widthFactor) t.widthFactor = float(requireRange(*ast_.widthFactor, "width factor", 1e-6, 1e6));
    if (ast_.elasticity) t.elasticity = float(requireRange(*ast_.elasticity, "elasticity", -1e3, 1e3));
    if (ast_.leafThickness)
      t.leafThickness = float(requireRange(*ast_.leafThickness, "leaf thickness", 0.0, 1.0));
    if (ast_.tropism) {
      for (int i = 0; i < 3; ++i) t.tropism[i] = float(requireConstant(*ast_.tropism->value[i], "tropism"));
    }
    for (int s = 1; s < kSectionCount; ++s)
      if (ast_.maxDepth[s]) g.maxDepth[s] = int(requireInteger(*ast_.maxDepth[s], "maximum depth", 1, kMaxDepthLimit));
    for (const syntax::LeafShapeDecl& d : ast_.leafShapes) {
      plant::LeafShape shape;
      shape.texture = texturePath(d.texture, d.pos);
      if (d.aspect) {
        shape.aspect = float(requireConstant(*d.aspect, "leaf aspect"));
        if (!(shape.aspect > 0.0f && shape.aspect <= 100.0f))
          error(d.aspect->pos, fmt::format("leaf aspect must lie in (0, 100], got {:g}", shape.aspect));
      }
      g.leafShapes.push_back(shape);
    }
    if (g.leafShapes.empty()) g.leafShapes.push_back({"builtin:ovate-0", 0.55f, Vec3::Ones()});
    for (const auto& c : ast_.colors) g.colors.push_back(color(c.value));
    if (g.colors.empty()) {
      // Leaf green, light green, petal yellow, white, red, violet, bark brown.
      g.colors = {Vec3(0.13f, 0.36f, 0.08f), Vec3(0.35f, 0.6f, 0.15f), Vec3(0.95f, 0.78f, 0.15f),
                  Vec3(0.92f, 0.92f, 0.88f), Vec3(0.75f, 0.1f, 0.1f),  Vec3(0.45f, 0.2f, 0.6f),
                  Vec3(0.42f, 0.32f, 0.22f)};
    }
    if (ast_.barkTexture) g.bark.texture = texturePath(ast_.barkTexture->value, ast_.barkTexture->pos);
    if (ast_.barkColor) g.bark.color = color(ast_.barkColor->value);
  }

  Vec3 color(const std::vector<syntax::ExprPtr>& v) {
    Vec3 c;
    for (int i = 0; i < 3; ++i) {
      c[i] = float(requireConstant(*v[i], "a colour component"));
      if (!(c[i] >= 0.0f && c[i] <= 1.0f)) error(v[i]->pos, "colour components lie in [0, 1] (linear RGB)");
    }
    return c;
  }

  std::string texturePath(const std::string& spec, SourcePos pos) {
    if (spec.empty()) error(pos, "texture is empty");
    if (io::isBuiltinTexture(spec)) {
      std::string name = spec.substr(io::kBuiltinPrefix.size());
      bool known = false;
      std::string list;
      for (std::string_view n : io::builtinTextureNames()) {
        known |= n == name;
        list += (list.empty() ? "" : ", ") + std::string(n);
      }
      if (!known) error(pos, fmt::format("unknown built-in texture \"{}\" (known: {})", spec, list));
      return spec;
    }
    std::filesystem::path p(spec);
    if (p.is_relative() && !options_.dir.empty()) p = options_.dir / p;
    return p.lexically_normal().string();
  }

  // --- modules -----------------------------------------------------------------------

  struct UserArity {
    int arity;
    SourcePos pos;
    bool declared;
  };

  uint16_t nameIndex(const std::string& name) {
    auto it = nameIndex_.find(name);
    if (it != nameIndex_.end()) return it->second;
    if (g_->names.size() >= 60000) error({}, "too many module names");
    g_->names.push_back(name);
    return nameIndex_[name] = uint16_t(g_->names.size() - 1);
  }

  // Checks a use of a module with `arity` parameters (patterns without parentheses pass -1).
  void checkArity(const std::string& name, int arity, SourcePos pos, const char* where) {
    if (const TurtleModule* t = findTurtleModule(name)) {
      if (arity >= 0 && (arity < t->minArity || arity > t->maxArity)) {
        std::string allowed = t->minArity == t->maxArity ? fmt::format("{}", t->minArity)
                              : t->maxArity == t->minArity + 1
                                  ? fmt::format("{} or {}", t->minArity, t->maxArity)
                                  : fmt::format("{} to {}", t->minArity, t->maxArity);
        error(pos, fmt::format("{} takes {} parameter{}, {} here{}", name, allowed, t->maxArity == 1 ? "" : "s",
                               arity, where));
      }
      return;
    }
    if (name[0] == '~') {
      if (arity > 1) error(pos, fmt::format("surface {} takes 0 or 1 parameter (a scale), {} here{}", name, arity, where));
      return;
    }
    if (arity < 0) return;
    auto it = userArity_.find(name);
    if (it == userArity_.end()) {
      userArity_[name] = {arity, pos, false};
    } else if (it->second.arity != arity) {
      error(pos, fmt::format("module {} has {} parameter{} here{} but {} {} at {}:{} (a module keeps its number of "
                             "parameters)",
                             name, arity, arity == 1 ? "" : "s", where, it->second.arity,
                             it->second.declared ? "in its module: declaration" : "where it is first used",
                             it->second.pos.line, it->second.pos.col));
    }
  }

  ModuleId moduleId(const std::string& name, int arity, SourcePos pos) {
    auto key = std::make_pair(name, arity);
    auto it = moduleIds_.find(key);
    if (it != moduleIds_.end()) return it->second;
    Grammar& g = *g_;
    if (g.modules.size() >= Grammar::kNoModule) error(pos, "too many different modules");
    ModuleInfo m;
    m.name = name;
    m.nameIndex = nameIndex(name);
    m.arity = uint8_t(arity);
    if (const TurtleModule* t = findTurtleModule(name)) {
      m.op = t->op;
    } else if (name[0] == '~') {
      m.op = TurtleOp::Surface;
      for (size_t i = 0; i < ast_.surfaces.size(); ++i)
        if (ast_.surfaces[i].name == name.substr(1)) m.surface = int16_t(i);
    }
    g.modules.push_back(m);
    ModuleId id = ModuleId(g.modules.size() - 1);
    if (name == "[") g.openId = id;
    if (name == "]") g.closeId = id;
    if (name == "%") g.cutId = id;
    return moduleIds_[key] = id;
  }

  // Every module written in an axiom, successor or surface gets its id now, so that
  // productions and ignore lists can be filed under them.
  void modules() {
    for (const syntax::ModuleDecl& d : ast_.moduleDecls) {
      if (findTurtleModule(d.name)) error(d.pos, fmt::format("{} is a turtle module and cannot be declared", d.name));
      if (!d.arity) continue;
      auto it = userArity_.find(d.name);
      if (it != userArity_.end() && it->second.arity != *d.arity)
        error(d.pos, fmt::format("module {} is declared twice with different parameter counts", d.name));
      userArity_[d.name] = {*d.arity, d.pos, true};
    }
    auto collect = [&](const syntax::ModuleString& s, const char* where) {
      for (const syntax::Module& m : s.modules) {
        checkArity(m.name, int(m.args.size()), m.pos, where);
        moduleId(m.name, int(m.args.size()), m.pos);
      }
    };
    if (ast_.axiom) collect(ast_.axiom->value, " in the axiom");
    for (const syntax::Production& p : ast_.productions) collect(p.successor, "");
    for (const syntax::SurfaceDecl& s : ast_.surfaces) collect(s.body, "");
    for (const ModuleInfo& m : g_->modules) produced_.insert(m.nameIndex);
    for (const syntax::ModuleDecl& d : ast_.moduleDecls)
      if (d.arity) moduleId(d.name, *d.arity, d.pos);
    // Patterns: arities must agree with the uses above.
    for (const syntax::Production& p : ast_.productions) {
      for (const auto* s : {&p.left, &p.right})
        for (const syntax::Module& m : s->modules) checkArity(m.name, m.parens ? int(m.args.size()) : -1, m.pos, "");
      checkArity(p.pred.name, p.pred.parens ? int(p.pred.args.size()) : -1, p.pred.pos, "");
      // A pattern with parameters names a module id even when nothing produces it.
      auto declare = [&](const syntax::Module& m) {
        if (m.parens) moduleId(m.name, int(m.args.size()), m.pos);
        else if (!findTurtleModule(m.name) && userArity_.count(m.name))
          moduleId(m.name, userArity_[m.name].arity, m.pos);
      };
      for (const auto* s : {&p.left, &p.right})
        for (const syntax::Module& m : s->modules) declare(m);
      declare(p.pred);
    }
  }

  // --- globals -----------------------------------------------------------------------

  int globalIndex(const std::string& name) const {
    const auto& names = g_->globalNames;
    auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : int(it - names.begin());
  }

  void addGlobal(const std::string& name, SourcePos pos, double value) {
    for (auto& [n, v] : defineValues_)
      if (n == name) error(pos, fmt::format("\"{}\" is a define: constant and cannot be a global variable", name));
    for (const Predefined& c : kConstants)
      if (name == c.name) error(pos, fmt::format("{} is a predefined constant", name));
    if (globalIndex(name) >= 0) return;
    if (g_->globalNames.size() >= 60000) error(pos, "too many global variables");
    g_->globalNames.push_back(name);
    g_->globalInit.push_back(value);
  }

  void assignedNames(const std::vector<Stmt>& stmts) {
    for (const Stmt& s : stmts) {
      if (s.kind == Stmt::Kind::Assign) addGlobal(s.name, s.pos, 0.0);
      assignedNames(s.body);
      assignedNames(s.otherwise);
    }
  }

  void globals() {
    for (const syntax::Assignment& a : ast_.globals) {
      if (globalIndex(a.name) >= 0) error(a.pos, fmt::format("global \"{}\" is declared twice", a.name));
      addGlobal(a.name, a.pos, requireConstant(*a.value, "a global's initial value"));
    }
    for (const auto* b : {&ast_.start, &ast_.startEach, &ast_.endEach, &ast_.end}) assignedNames(*b);
  }

  // --- code generation ---------------------------------------------------------------

  enum class ScopeKind { Block, Axiom, Production, Surface };

  struct Scope {
    ScopeKind kind = ScopeKind::Block;
    Section section = Section::Production;
    std::vector<std::pair<std::string, uint16_t>> slots;
    uint16_t params = 0;  // the first slots are bound parameters (read-only)
    bool writesGlobals = false;
  };

  bool scopeHas(const std::string& name) const {
    if (!scope_) return false;
    for (auto& [n, s] : scope_->slots)
      if (n == name) return true;
    return false;
  }

  struct Builder {
    Program prog;
    int depth = 0;
    void emit(Instr in, int delta) {
      prog.code.push_back(in);
      depth += delta;
      prog.maxStack = uint16_t(std::max<int>(prog.maxStack, depth));
    }
    size_t here() const { return prog.code.size(); }
  };

  void expr(const Expr& e, Builder& b) {
    if (auto v = constant(e)) {
      if (!std::isfinite(*v)) error(e.pos, "the value is not a finite number");
      b.emit({Op::Const, 0, 0, 0, *v}, 1);
      return;
    }
    switch (e.kind) {
      case Expr::Kind::Number: b.emit({Op::Const, 0, 0, 0, e.value}, 1); return;
      case Expr::Kind::Name: {
        if (scope_)
          for (auto& [n, s] : scope_->slots)
            if (n == e.name) {
              b.emit({Op::Load, 0, uint32_t(s), 0, 0}, 1);
              return;
            }
        int gi = globalIndex(e.name);
        if (gi >= 0) {
          if (scope_ && scope_->kind == ScopeKind::Surface)
            error(e.pos, "surfaces are built once, before Start: runs; they cannot use global variables");
          b.emit({Op::LoadGlobal, 0, uint32_t(gi), 0, 0}, 1);
          return;
        }
        unknownName(e);
      }
      case Expr::Kind::Unary:
        expr(*e.args[0], b);
        b.emit({e.op == '-' ? Op::Neg : Op::Not, 0, 0, 0, 0}, 0);
        return;
      case Expr::Kind::Binary: {
        expr(*e.args[0], b);
        expr(*e.args[1], b);
        Op op = Op::Add;
        switch (e.op) {
          case '+': op = Op::Add; break;
          case '-': op = Op::Sub; break;
          case '*': op = Op::Mul; break;
          case '/': op = Op::Div; break;
          case '%': op = Op::Mod; break;
          case '^': op = Op::Pow; break;
          case '<': op = Op::Lt; break;
          case 'L': op = Op::Le; break;
          case '>': op = Op::Gt; break;
          case 'G': op = Op::Ge; break;
          case '=': op = Op::Eq; break;
          case 'N': op = Op::Ne; break;
        }
        b.emit({op, 0, 0, loc(e.pos), 0}, -1);
        return;
      }
      case Expr::Kind::And:
      case Expr::Kind::Or: {
        // a && b: (a ? (b != 0) : 0); a || b: (a ? 1 : (b != 0)).
        bool isAnd = e.kind == Expr::Kind::And;
        expr(*e.args[0], b);
        size_t jumpA = b.here();
        b.emit({Op::JumpIfZero, 0, 0, 0, 0}, -1);
        if (isAnd) {
          expr(*e.args[1], b);
          b.emit({Op::Const, 0, 0, 0, 0.0}, 1);
          b.emit({Op::Ne, 0, 0, 0, 0}, -1);
        } else {
          b.emit({Op::Const, 0, 0, 0, 1.0}, 1);
        }
        size_t jumpEnd = b.here();
        b.emit({Op::Jump, 0, 0, 0, 0}, 0);
        b.depth -= 1;
        patch(b, jumpA);
        if (isAnd) {
          b.emit({Op::Const, 0, 0, 0, 0.0}, 1);
        } else {
          expr(*e.args[1], b);
          b.emit({Op::Const, 0, 0, 0, 0.0}, 1);
          b.emit({Op::Ne, 0, 0, 0, 0}, -1);
        }
        patch(b, jumpEnd);
        return;
      }
      case Expr::Kind::Ternary: {
        expr(*e.args[0], b);
        size_t jumpElse = b.here();
        b.emit({Op::JumpIfZero, 0, 0, 0, 0}, -1);
        expr(*e.args[1], b);
        size_t jumpEnd = b.here();
        b.emit({Op::Jump, 0, 0, 0, 0}, 0);
        b.depth -= 1;
        patch(b, jumpElse);
        expr(*e.args[2], b);
        patch(b, jumpEnd);
        return;
      }
      case Expr::Kind::Call: {
        Fn f = function(e);
        if (fnInfo(f).random && scope_ && scope_->kind == ScopeKind::Surface)
          error(e.pos, "surfaces are built once; they cannot draw random numbers");
        for (const auto& a : e.args) expr(*a, b);
        int n = int(e.args.size());
        b.emit({Op::Call, uint8_t(f), uint32_t(n), loc(e.pos), 0}, 1 - n);
        return;
      }
    }
  }

  void patch(Builder& b, size_t at) {
    if (b.here() > kMaxProgram) error({}, "a production or block is too long to compile");
    b.prog.code[at].b = uint32_t(b.here());
  }

  void statements(const std::vector<Stmt>& stmts, Builder& b) {
    for (const Stmt& s : stmts) statement(s, b);
  }

  void statement(const Stmt& s, Builder& b) {
    switch (s.kind) {
      case Stmt::Kind::Block: statements(s.body, b); return;
      case Stmt::Kind::If: {
        expr(*s.value, b);
        size_t jumpElse = b.here();
        b.emit({Op::JumpIfZero, 0, 0, 0, 0}, -1);
        statements(s.body, b);
        if (s.otherwise.empty()) {
          patch(b, jumpElse);
          return;
        }
        size_t jumpEnd = b.here();
        b.emit({Op::Jump, 0, 0, 0, 0}, 0);
        patch(b, jumpElse);
        statements(s.otherwise, b);
        patch(b, jumpEnd);
        return;
      }
      case Stmt::Kind::Assign: {
        Scope& sc = *scope_;
        for (auto& [n, v] : defineValues_)
          if (n == s.name) error(s.pos, fmt::format("cannot assign to the define: constant \"{}\"", s.name));
        for (const Predefined& c : kConstants)
          if (s.name == c.name) error(s.pos, fmt::format("cannot assign to the predefined constant {}", s.name));
        // The target: a local or parameter slot, else a global, else a new local.
        int slot = -1;
        for (size_t i = 0; i < sc.slots.size(); ++i)
          if (sc.slots[i].first == s.name) slot = int(i);
        if (slot >= 0 && slot < sc.params)
          error(s.pos, fmt::format("cannot assign to the parameter \"{}\" (assign to a new local name)", s.name));
        int gi = slot < 0 ? globalIndex(s.name) : -1;
        if (slot < 0 && gi < 0) {
          if (sc.kind != ScopeKind::Production) error(s.pos, fmt::format("unknown name \"{}\"", s.name));
          if (sc.slots.size() >= 60000) error(s.pos, "too many local variables");
          sc.slots.emplace_back(s.name, uint16_t(sc.slots.size()));
          slot = int(sc.slots.size() - 1);
        }
        if (gi >= 0) {
          if (sc.kind == ScopeKind::Production && sc.section == Section::Interpretation)
            error(s.pos, fmt::format("interpretation rules cannot assign the global variable \"{}\" (interpretation "
                                     "must not change the L-system)",
                                     s.name));
          sc.writesGlobals = true;
        }
        if (s.op != '=') {
          if (gi >= 0) b.emit({Op::LoadGlobal, 0, uint32_t(gi), 0, 0}, 1);
          else b.emit({Op::Load, 0, uint32_t(slot), 0, 0}, 1);
        }
        expr(*s.value, b);
        if (s.op != '=') {
          Op op = s.op == '+' ? Op::Add : s.op == '-' ? Op::Sub : s.op == '*' ? Op::Mul : Op::Div;
          b.emit({op, 0, 0, loc(s.pos), 0}, -1);
        }
        if (gi >= 0) b.emit({Op::StoreGlobal, 0, uint32_t(gi), loc(s.pos), 0}, -1);
        else b.emit({Op::Store, 0, uint32_t(slot), 0, 0}, -1);
        return;
      }
    }
  }

  Program finish(Builder& b, bool halt = true) {
    if (halt) b.emit({Op::Halt, 0, 0, 0, 0}, 0);
    if (b.prog.code.size() > kMaxProgram) error({}, "a production or block is too long to compile");
    if (b.prog.maxStack > kMaxStackDepth) error({}, "an expression is too deeply nested to compile");
    g_->maxStack = std::max(g_->maxStack, b.prog.maxStack);
    return std::move(b.prog);
  }

  Program block(const std::vector<Stmt>& stmts, const char* what) {
    if (stmts.empty()) return {};
    Scope scope;
    scope.kind = ScopeKind::Block;
    scope_ = &scope;
    Builder b;
    statements(stmts, b);
    scope_ = nullptr;
    (void)what;
    return finish(b);
  }

  // A successor (or axiom, or surface body): each module's parameters, then Emit.
  Program successor(const syntax::ModuleString& s, Scope& scope, const char* what) {
    Scope* saved = scope_;
    scope_ = &scope;
    Builder b;
    int depth = 0;
    for (const syntax::Module& m : s.modules) {
      if (m.name == "[") ++depth;
      if (m.name == "]" && --depth < 0) error(m.pos, fmt::format("] without a matching [ in the {}", what));
      if (m.name == "?E" && !m.args.empty())
        if (auto kind = constant(*m.args[0])) checkQueryKind(*kind, int(m.args.size()), m.args[0]->pos);
      for (const auto& a : m.args) expr(*a, b);
      ModuleId id = moduleId(m.name, int(m.args.size()), m.pos);
      int n = int(m.args.size());
      b.emit({Op::Emit, uint8_t(n), uint32_t(id), loc(m.pos), 0}, -n);
    }
    if (depth != 0) error(s.pos, fmt::format("the {} opens {} more [ than it closes", what, depth));
    scope_ = saved;
    return finish(b);
  }

  void checkQueryKind(double kind, int arity, SourcePos pos) {
    if (std::string problem = queryProblem(kind, arity); !problem.empty()) error(pos, problem);
  }

  static bool emitsCut(const syntax::ModuleString& s) {
    for (const syntax::Module& m : s.modules)
      if (m.name == "%") return true;
    return false;
  }

  // --- productions -------------------------------------------------------------------

  void bind(const syntax::Module& m, Scope& scope) {
    for (const auto& a : m.args) {
      for (auto& [n, s] : scope.slots)
        if (n == a->name) error(a->pos, fmt::format("parameter \"{}\" is bound twice in this production", a->name));
      for (auto& [n, v] : defineValues_)
        if (n == a->name) error(a->pos, fmt::format("parameter \"{}\" has the name of a define: constant", a->name));
      if (scope.slots.size() >= 60000) error(a->pos, "too many parameters");
      scope.slots.emplace_back(a->name, uint16_t(scope.slots.size()));
    }
  }

  PatternItem patternModule(const syntax::Module& m, uint16_t slot) {
    PatternItem it;
    it.kind = PatternItem::Kind::Module;
    it.nameIndex = nameIndex(m.name);
    it.arity = m.parens ? int16_t(m.args.size()) : int16_t(-1);
    it.slot = slot;
    return it;
  }

  void productions() {
    Grammar& g = *g_;
    std::map<std::pair<uint16_t, int16_t>, int32_t> openGroups;
    int32_t groups = 0;
    for (const syntax::Production& sp : ast_.productions) {
      Production p;
      p.section = sp.section;
      p.pos = sp.pos;
      p.text = sp.text;
      const char* sectionName = sp.section == Section::Production      ? "production"
                                : sp.section == Section::Decomposition ? "decomposition rule"
                                                                       : "interpretation rule";
      if (sp.section != Section::Production && (sp.hasLeft || sp.hasRight))
        error(sp.pos, fmt::format("a {} cannot have a context (only productions can)", sectionName));
      if ((sp.hasLeft && sp.left.modules.empty()) || (sp.hasRight && sp.right.modules.empty()))
        error(sp.pos, "a context after < or before > is empty");
      const std::string& pn = sp.pred.name;
      if (pn == "[" || pn == "]")
        error(sp.pred.pos, "brackets cannot be rewritten (they keep the string's branches balanced)");
      if (pn == "%") error(sp.pred.pos, "% cannot be rewritten: it cuts its branch in the step that produces it");
      Scope scope;
      scope.kind = ScopeKind::Production;
      scope.section = sp.section;
      // Slots in the order written: left context, predecessor, right context.
      for (const syntax::Module& m : sp.left.modules) {
        if (m.name == "[" || m.name == "]") error(m.pos, "a left context cannot contain brackets");
        p.left.push_back(patternModule(m, uint16_t(scope.slots.size())));
        bind(m, scope);
      }
      p.predName = nameIndex(pn);
      p.predArity = sp.pred.parens ? int16_t(sp.pred.args.size()) : int16_t(-1);
      p.predSlot = uint16_t(scope.slots.size());
      bind(sp.pred, scope);
      std::vector<size_t> open;
      for (const syntax::Module& m : sp.right.modules) {
        PatternItem it;
        if (m.name == "[") {
          if (m.parens) error(m.pos, "[ takes no parameters");
          it.kind = PatternItem::Kind::Open;
          open.push_back(p.right.size());
        } else if (m.name == "]") {
          if (m.parens) error(m.pos, "] takes no parameters");
          if (open.empty()) error(m.pos, "] without a matching [ in the right context");
          it.kind = PatternItem::Kind::Close;
          it.partner = int32_t(open.back());
          p.right[open.back()].partner = int32_t(p.right.size());
          open.pop_back();
        } else {
          it = patternModule(m, uint16_t(scope.slots.size()));
          bind(m, scope);
        }
        p.right.push_back(it);
      }
      if (!open.empty()) error(sp.right.pos, "the right context opens a [ that it does not close");
      scope.params = uint16_t(scope.slots.size());

      scope_ = &scope;
      if (!sp.pre.empty() || sp.condition || !sp.post.empty()) {
        Builder b;
        statements(sp.pre, b);
        size_t jumpFail = 0;
        bool conditional = sp.condition != nullptr;
        if (conditional) {
          expr(*sp.condition, b);
          jumpFail = b.here();
          b.emit({Op::JumpIfZero, 0, 0, 0, 0}, -1);
        }
        statements(sp.post, b);
        b.emit({Op::Const, 0, 0, 0, 1.0}, 1);
        b.emit({Op::Return, 0, 0, 0, 0}, -1);
        if (conditional) {
          patch(b, jumpFail);
          b.emit({Op::Const, 0, 0, 0, 0.0}, 1);
          b.emit({Op::Return, 0, 0, 0, 0}, -1);
        }
        p.match = finish(b, false);
      }
      if (sp.probability) {
        Builder b;
        expr(*sp.probability, b);
        b.emit({Op::Return, 0, 0, 0, 0}, -1);
        p.weight = finish(b, false);
      }
      scope_ = nullptr;
      p.successor = successor(sp.successor, scope, sectionName);
      p.paramCount = scope.params;
      p.frameSize = uint16_t(scope.slots.size());
      g.maxFrame = std::max(g.maxFrame, p.frameSize);
      if (scope.writesGlobals && sp.section != Section::Interpretation) g.sequential = true;
      if (sp.section == Section::Production) g.producesCut |= emitsCut(sp.successor);
      if (sp.section == Section::Decomposition) g.producesCut |= emitsCut(sp.successor);
      g.hasContext |= p.hasContext();

      // Stochastic groups: productions with probabilities for the same predecessor, with no
      // production without one for it in between.
      auto key = std::make_pair(p.predName, p.predArity);
      if (sp.probability) {
        auto it = openGroups.find(key);
        if (it == openGroups.end()) it = openGroups.emplace(key, groups++).first;
        p.group = it->second;
      } else {
        openGroups.erase(key);
      }
      if (sp.section == Section::Production && !produced_.count(p.predName))
        log::warn("{}:{}:{}: this production rewrites {}, which neither the axiom nor any successor produces",
                  g.source, sp.pos.line, sp.pos.col, pn);
      g.productions.push_back(std::move(p));
    }
  }

  void contextSets() {
    Grammar& g = *g_;
    g.ignored.assign(g.modules.size(), 0);
    const syntax::ModuleString* list = ast_.ignore ? &*ast_.ignore : ast_.consider ? &*ast_.consider : nullptr;
    if (!list) return;
    std::set<uint16_t> names;
    for (const syntax::Module& m : list->modules) {
      if (m.parens) error(m.pos, "ignore: and consider: list module names without parameters");
      if (m.name == "[" || m.name == "]") error(m.pos, "brackets are always considered; they cannot be listed");
      auto it = nameIndex_.find(m.name);
      if (it == nameIndex_.end())
        error(m.pos, fmt::format("unknown module {}: no axiom, successor or production uses it", m.name));
      names.insert(it->second);
    }
    bool ignore = ast_.ignore.has_value();
    for (ModuleId id = 0; id < g.modules.size(); ++id) {
      if (g.modules[id].op == TurtleOp::Push || g.modules[id].op == TurtleOp::Pop) continue;
      bool listed = names.count(g.modules[id].nameIndex) > 0;
      g.ignored[id] = ignore ? listed : !listed;
    }
  }

  void surfaces() {
    Grammar& g = *g_;
    for (const syntax::SurfaceDecl& d : ast_.surfaces) {
      for (const syntax::Module& m : d.body.modules) {
        if (m.name == "~leaf") error(m.pos, "~leaf places a PlantModel leaf; it cannot be part of a surface");
        if (m.name[0] == '?') error(m.pos, "queries cannot be part of a surface");
      }
      Scope scope;
      scope.kind = ScopeKind::Surface;
      Program prog = successor(d.body, scope, "surface");
      LString s;
      StringSink sink(s, g);
      std::vector<double> stack(prog.maxStack + 1);
      LazyRng rng(RandomKey{});
      RunContext c;
      c.stack = stack.data();
      c.rng = &rng;
      c.sink = &sink;
      try {
        run(prog, c);
      } catch (const EvalFailure& f) {
        error(g.locations[f.loc], f.message);
      }
      Surface surface;
      surface.name = d.name;
      surface.meshes = surfaceMeshes(g, s);
      g.surfaces.push_back(std::move(surface));
    }
  }

  const syntax::Grammar& ast_;
  const CompileOptions& options_;
  std::shared_ptr<Grammar> g_;
  std::vector<std::pair<std::string, double>> defineValues_;
  std::map<std::string, uint16_t> nameIndex_;
  std::map<std::pair<std::string, int>, ModuleId> moduleIds_;
  std::map<std::string, UserArity> userArity_;
  std::set<uint16_t> produced_;  // names the axiom, successors and surfaces write
  Scope* scope_ = nullptr;
};

}  // namespace

std::shared_ptr<const Grammar> compileGrammar(std::string_view text, const std::string& source,
                                              const CompileOptions& options) {
  syntax::Grammar ast = parseGrammar(text, source);
  return Compiler(ast, source, options).compile();
}

}  // namespace tendril::lsystem
