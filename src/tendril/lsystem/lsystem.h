// L-systems in Tendril (docs/grammar.md): a grammar language familiar to cpfg and L-Py users —
// parametric modules, context-sensitive, conditional and stochastic productions, decomposition
// and interpretation rules, global variables, query and environment modules — and a turtle
// that draws the string as a PlantModel.
//
//   auto grammar = lsystem::loadGrammarFile("examples/grammars/abop-1.24a.ls");
//   lsystem::LSystem ls(grammar);
//   ls.derive();                          // to the grammar's derivation length
//   plant::PlantModel plant = ls.interpret();
//
// A Grammar is shared and immutable; an LSystem is one plant's derivation (its string, global
// variables and step count). Results depend only on the grammar, the seed and the environment,
// never on the thread count.
#pragma once

#include "tendril/core/archive.h"
#include "tendril/env/environment.h"
#include "tendril/lsystem/compiler.h"
#include "tendril/lsystem/derivation.h"
#include "tendril/lsystem/diagnostic.h"
#include "tendril/lsystem/grammar.h"
#include "tendril/lsystem/grammar_files.h"
#include "tendril/lsystem/lstring.h"
#include "tendril/lsystem/turtle.h"
#include "tendril/plant/plant_model.h"

#include <memory>
#include <optional>
#include <string>

namespace tendril::lsystem {

struct RunOptions {
  std::optional<uint64_t> seed;         // default: the grammar's seed:
  uint64_t plant = 0;                   // plant id (a random key, like the seed)
  std::optional<int> derivationLength;  // default: the grammar's derivation length:
  std::optional<Limits> limits;         // default: the grammar's (max length:)
  TurtleStart start;                    // where the plant stands, for interpretation and queries
  float stepTime = 1.0f;                // seconds of node age per derivation step
  // Growth-Flow constants (seed 001): each derivation step records the wind at the plant's
  // start position as one unit of growth time, and interpretation applies it (InterpretOptions).
  plant::GrowthFlowSpecies growthFlow;
};

class LSystem {
 public:
  // Runs Start: and makes the axiom (decomposed). Throws Error for run-time errors there.
  explicit LSystem(std::shared_ptr<const Grammar> grammar, const RunOptions& options = {});
  ~LSystem();
  LSystem(LSystem&&) noexcept;
  LSystem& operator=(LSystem&&) noexcept;

  // One derivation step (nothing once finished): StartEach:, productions, decomposition, the
  // cut, then query modules are answered (?E by `env`, null = an empty world), EndEach:, and
  // End: after the last step.
  void step(const env::Environment* env = nullptr);
  // Steps until finished.
  void derive(const env::Environment* env = nullptr);
  // Answers the query modules of the current string (done by step(); needed by hand only to
  // see the answers for the axiom before the first step).
  void answerQueries(const env::Environment* env = nullptr);

  bool finished() const { return int(step_) >= derivationLength_; }
  uint32_t stepCount() const { return step_; }
  int derivationLength() const { return derivationLength_; }
  uint64_t seed() const { return context_.seed; }

  const Grammar& grammar() const { return *grammar_; }
  std::shared_ptr<const Grammar> sharedGrammar() const { return grammar_; }
  const LString& string() const { return current_; }
  // The string as text, e.g. "F[+F]F" (at most maxModules modules).
  std::string text(size_t maxModules = SIZE_MAX) const { return formatString(*grammar_, current_, maxModules); }
  // A global variable's value; throws Error for an unknown name.
  double global(std::string_view name) const;
  // Modules drawn as segments (F) in the string: a cheap size for progress reports.
  size_t segmentModules() const;

  // The plant the current string draws.
  plant::PlantModel interpret() const;
  // The wind recorded so far (one unit per derivation step).
  const plant::GrowthFlowHistory& windHistory() const { return wind_; }

  // The derivation's state (string, globals, step; sessions and undo, lsystem_state.cpp).
  // loadState expects an LSystem made from the same grammar and options.
  void saveState(ArchiveWriter& out) const;
  void loadState(ArchiveReader& in);

 private:
  InterpretOptions interpretOptions() const;
  void block(const Program& p, const char* name, uint64_t which);

  std::shared_ptr<const Grammar> grammar_;
  RunOptions options_;
  DeriveContext context_;
  int derivationLength_ = 0;
  uint32_t step_ = 0;
  std::vector<double> globals_;
  LString current_, next_;
  DeriveScratch scratch_;
  bool answered_ = false;
  plant::GrowthFlowHistory wind_;
};

}  // namespace tendril::lsystem
