// User functions in graph files: muParser expressions compiled once, evaluated many times.
//
// seed 004, "Functional modeling": wherever a component uses a parameter interval, "a
// function can be applied before the system uses the interpolated parameters of that
// interval"; sine, cosine, a random function, the recursion depth and the iteration number
// may appear in it. The sandbox knows only the variables a parameter allows (see VarMask) and
// the functions listed in docs/graph-format.md; anything else is an Error naming the file and
// the JSON pointer of the expression. Assignments and several comma-separated results are
// rejected, so an expression cannot change its inputs.
//
// Random functions draw from a tendril::Rng keyed by the caller (graph seed, component,
// instance path, slot, parameter): the same instance gets the same numbers whatever the order
// of evaluation or the thread count.
//
// An Expression is not thread-safe (muParser keeps its evaluation stack inside the parser):
// every expansion compiles its own set (see expand.cpp).
#pragma once

#include "tendril/core/random.h"

#include <cstdint>
#include <memory>
#include <string>

namespace mu {
class Parser;
}

namespace tendril::graph {

// The variables an expression may use. Which ones a parameter offers is listed with the
// parameter in docs/graph-format.md.
enum VarMask : uint32_t {
  kVarI = 1u << 0,      // iteration number from the nearest multiplier, 0 .. n-1
  kVarN = 1u << 1,      // number of iterations of that multiplier
  kVarT = 1u << 2,      // i / (n - 1) (0 when n = 1)
  kVarDepth = 1u << 3,  // recursion level, 1 for the first instance of a recursive component
  kVarV = 1u << 4,      // the interpolated range value (range + function parameters)
  kVarS = 1u << 5,      // position along a stem, 0 at the base .. 1 at the tip
  kVarXyz = 1u << 6,    // x, y, z: a point (FFD: local coordinates; World: world position)
};
inline constexpr uint32_t kInstanceVars = kVarI | kVarN | kVarT | kVarDepth;

struct EvalVars {
  double i = 0, n = 1, t = 0, depth = 0, v = 0, s = 0, x = 0, y = 0, z = 0;
};

class Expression {
 public:
  // Compiles `text`. Errors (syntax, unknown names, assignments, a constant that is not
  // finite) are Error(source, pointer, ...).
  Expression(const std::string& text, uint32_t vars, std::string source, std::string pointer);
  ~Expression();
  Expression(const Expression&) = delete;
  Expression& operator=(const Expression&) = delete;

  // Evaluates with the given variables; `key` seeds rand()/jitter()/normal() (may be null
  // when usesRandom() is false). A result that is not finite is an Error naming the
  // expression and the variables.
  double eval(const EvalVars& vars, const RandomKey* key) const;
  // The variables this expression may use and their values, e.g. "i=2, n=5, t=0.5, depth=0"
  // (for messages).
  std::string inputs(const EvalVars& vars) const;

  bool usesRandom() const { return usesRandom_; }
  // No variables and no random functions: the value never changes.
  bool isConstant() const { return constant_; }
  double constantValue() const { return constantValue_; }
  const std::string& text() const { return text_; }
  const std::string& source() const { return source_; }
  const std::string& pointer() const { return pointer_; }

 private:
  struct State;
  std::string text_, source_, pointer_;
  uint32_t vars_ = 0;
  bool usesRandom_ = false;
  bool constant_ = false;
  double constantValue_ = 0;
  std::unique_ptr<State> state_;
  std::unique_ptr<mu::Parser> parser_;
};

// Names of the variables in `mask`, e.g. "i, n, t, depth" (for messages and docs).
std::string variableNames(uint32_t mask);

}  // namespace tendril::graph
