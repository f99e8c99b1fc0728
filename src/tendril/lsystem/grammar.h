// A compiled L-system grammar (docs/grammar.md): shared, immutable, made once by
// compileGrammar() and used by any number of LSystem instances. Modules are small ids,
// productions are bytecode (program.h), and every production is filed under the module ids it
// can rewrite, so deriving never looks at text.
#pragma once

#include "tendril/core/math.h"
#include "tendril/core/triangle_mesh.h"
#include "tendril/lsystem/lstring.h"
#include "tendril/lsystem/program.h"
#include "tendril/plant/plant_model.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace tendril::lsystem {

// What the turtle does with a module (ABOP §1.3, §1.5, §1.9 and cpfg's extensions).
enum class TurtleOp : uint8_t {
  None,            // a user module: no geometry
  Forward,         // F, F(l): draw a segment (a PlantModel node)
  Move,            // f, f(l): move without drawing
  TurnLeft,        // +, +(a): about U
  TurnRight,       // -
  PitchDown,       // &: about L
  PitchUp,         // ^
  RollLeft,        // \ : about H
  RollRight,       // /
  TurnAround,      // |
  RollHorizontal,  // $: L horizontal (ABOP §1.5)
  Push,            // [
  Pop,             // ]
  Width,           // !, !(w)
  Color,           // ', '(i)
  PolygonBegin,    // {
  PolygonEnd,      // }
  Vertex,          // .
  Cut,             // %
  SetHeading,      // @R(hx,hy,hz[,ux,uy,uz])
  MoveTo,          // @M(x,y,z)
  TropismVector,   // @Tv(x,y,z)
  Elasticity,      // @Te(e)
  Sphere,          // @O, @O(r)
  Climbing,        // @Climb(c): following segments are flagged as climbing
  Leaf,            // ~leaf(size[, shape[, petiole]])
  Surface,         // ~name, ~name(scale): a predefined surface
  QueryPosition,   // ?P(x,y,z)
  QueryHeading,    // ?H
  QueryUp,         // ?U
  QueryLeft,       // ?L
  QueryEnvironment,  // ?E(kind, ...)
};

inline bool isQuery(TurtleOp op) { return op >= TurtleOp::QueryPosition; }

// Kinds of environment query, the first parameter of ?E (predefined constants SURFACE, HIT,
// LIGHT, ATTRACT and FACING). See docs/grammar.md for the parameters each one fills.
enum class QueryKind : int { Surface = 1, Hit = 2, Light = 3, Attract = 4, Facing = 5 };
inline constexpr int kQueryKinds = 5;
// The parameter counts a ?E query of a kind accepts: {min, max}.
std::pair<int, int> queryArity(QueryKind kind);
// Why a ?E module whose first parameter is `kind` and which has `count` parameters cannot be
// answered; empty when it can. Checked where the module is written when the kind is a
// constant, otherwise where a rule emits it, so that the error names the rule.
std::string queryProblem(double kind, int count);

struct ModuleInfo {
  std::string name;  // as written: "F", "@R", "?E", "~leaf", "Apex"
  uint16_t nameIndex = 0;  // modules with the same name share it (F and F(l))
  uint8_t arity = 0;
  TurtleOp op = TurtleOp::None;
  int16_t surface = -1;  // TurtleOp::Surface: index into Grammar::surfaces
};

// A location in the grammar text (1-based), for messages.
struct SourcePos {
  uint32_t line = 0, col = 0;
};

enum class Section : uint8_t { Production = 0, Decomposition = 1, Interpretation = 2 };
inline constexpr int kSectionCount = 3;

// One module of a context pattern, or a bracket of a right context.
struct PatternItem {
  enum class Kind : uint8_t { Module, Open, Close };
  Kind kind = Kind::Module;
  uint16_t nameIndex = 0;
  int16_t arity = -1;   // -1: written without parentheses, matches any parameter count
  uint16_t slot = 0;    // where its parameters are bound
  int32_t partner = -1;  // Open/Close: index of the matching bracket in the pattern
};

struct Production {
  Section section = Section::Production;
  SourcePos pos;
  std::string text;  // the production as written (one line), for messages
  uint16_t predName = 0;
  int16_t predArity = -1;
  uint16_t predSlot = 0;
  std::vector<PatternItem> left, right;  // left context (no brackets), right context
  uint16_t paramCount = 0;               // slots bound from the pattern; locals follow
  uint16_t frameSize = 0;                // bound parameters + locals
  Program match;                         // pre-condition block, condition, post block; empty = always
  Program weight;                        // probability; empty unless stochastic
  Program successor;
  int32_t group = -1;  // stochastic group (consecutive productions with probabilities)
  bool hasContext() const { return !left.empty() || !right.empty(); }
};

// A predefined surface (`surface: name = ...`): polygons in the surface's own frame (turtle
// heading +Y, up +Z) at scale 1, one mesh per colour index.
struct Surface {
  std::string name;
  std::vector<std::pair<int, TriangleMesh>> meshes;
};

// Turtle settings from the grammar's directives.
struct TurtleSettings {
  float angle = radians(90.0f);  // default turn angle δ (radians; degrees in the file)
  float step = 1.0f;             // default F / f length
  float width = 0.1f;            // initial segment width (diameter)
  float widthFactor = 0.7f;      // `!` without parameter multiplies the width by this
  Vec3 tropism = Vec3::Zero();   // ABOP §2.4 tropism vector T
  float elasticity = 0.0f;       // ABOP §2.4 susceptibility e
  float leafThickness = 0.0004f;
};

// Run-time limits: exceeding one is an Error saying which limit to raise.
inline constexpr size_t kParamsPerModule = 8;
struct Limits {
  size_t maxModules = 20'000'000;                     // string length, and modules drawn per pass
  size_t maxParams = kParamsPerModule * 20'000'000;   // parameter values in the string
};

class Grammar {
 public:
  std::string name;    // `lsystem:` name, or the file name
  std::string source;  // how errors name the grammar (its path)
  std::filesystem::path dir;  // relative texture paths resolve here

  std::vector<ModuleInfo> modules;
  std::vector<std::string> names;  // by nameIndex
  std::vector<std::string> globalNames;
  std::vector<double> globalInit;
  std::vector<std::pair<std::string, double>> defines;  // final values, in file order

  std::vector<Production> productions;  // all sections, in file order
  // Per section and module id: indices of the productions that may rewrite it, in file order.
  std::array<std::vector<std::vector<uint32_t>>, kSectionCount> candidates;
  std::vector<uint8_t> ignored;  // per module id: skipped when matching contexts

  Program axiom;  // emits the axiom
  Program start, startEach, endEach, end;

  int derivationLength = 1;
  uint64_t seed = 0;
  std::array<int, kSectionCount> maxDepth{1, 1, 1};  // decomposition / interpretation depth
  Limits limits;

  TurtleSettings turtle;
  std::vector<plant::LeafShape> leafShapes;
  std::vector<Vec3> colors;  // polygon / sphere colours by colour index (linear RGB)
  plant::BarkMaterial bark;
  std::vector<Surface> surfaces;

  std::vector<SourcePos> locations;  // Instr::loc indexes this

  // Facts the engine uses to skip work.
  uint16_t maxFrame = 0;  // largest production frame
  uint16_t maxStack = 0;  // largest program stack
  uint32_t maxGroup = 0;  // most members of one stochastic group among one module's candidates
  bool hasQueries = false;          // some module may be a query (filled by interpretation)
  bool producesCut = false;         // some successor contains %
  bool hasContext = false;          // some production has a context (needs the bracket table)
  bool sequential = false;          // productions or decompositions assign globals: derive in order
  ModuleId openId = kNoModule, closeId = kNoModule;  // [ and ] (absent when unused)
  ModuleId cutId = kNoModule;

  static constexpr ModuleId kNoModule = std::numeric_limits<ModuleId>::max();

  const ModuleInfo& module(ModuleId id) const { return modules[id]; }
  size_t moduleCount() const { return modules.size(); }
  const std::vector<uint32_t>& candidatesFor(Section s, ModuleId id) const {
    return candidates[size_t(s)][id];
  }
  bool hasRules(Section s) const;
  // Index of a global variable, or -1.
  int globalIndex(std::string_view name) const;
  // "line:col" of a program location.
  std::string location(uint32_t loc) const;
};

// "A(1, 2.5)": a module with its parameters, for messages and printing.
std::string formatModule(const Grammar& g, ModuleId id, const float* params, uint32_t count);
// The whole string (or its first maxModules modules, then "…").
std::string formatString(const Grammar& g, const LString& s, size_t maxModules = SIZE_MAX);

}  // namespace tendril::lsystem
