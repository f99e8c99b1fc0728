// One derivation step of a compiled grammar: parallel rewriting of every module by the first
// production whose predecessor, contexts (ABOP §1.8, bracket-aware, with ignore:/consider:) and
// condition (ABOP §1.10) match — a stochastic group (ABOP §1.7) picks one of its matching
// members with probability proportional to its weight — then decomposition of what was
// produced (to the section's maximum depth), then the cut (%).
//
// The input is split into fixed-size chunks rewritten in parallel into their own buffers and
// concatenated; random numbers are keyed by (seed, plant, module index, step, purpose), so the
// result does not depend on the thread count. When productions assign global variables the
// step runs in string order on one thread instead.
#pragma once

#include "tendril/core/error.h"
#include "tendril/lsystem/grammar.h"
#include "tendril/lsystem/lstring.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace tendril::lsystem {

inline constexpr uint64_t kPurposeProduction = purposeId("lsystem.production");
inline constexpr uint64_t kPurposeDecomposition = purposeId("lsystem.decomposition");
inline constexpr uint64_t kPurposeInterpretation = purposeId("lsystem.interpretation");
inline constexpr uint64_t kPurposeAxiom = purposeId("lsystem.axiom");
inline constexpr uint64_t kPurposeBlock = purposeId("lsystem.block");

// The key of the k-th module emitted by a rule applied at `path` (decomposition and
// interpretation rules key their random numbers by it).
inline uint64_t childPath(uint64_t path, uint32_t k) { return mix64(path ^ (uint64_t(k) + 1) * 0x9e3779b97f4a7c15ull); }

struct DeriveContext {
  uint64_t seed = 0;
  uint64_t plant = 0;
  uint32_t step = 0;  // the step being made; new modules are born in it
  double* globals = nullptr;
  Limits limits;
};

// Reusable buffers of a derivation (per LSystem), so steps do not reallocate.
class DeriveScratch {
 public:
  DeriveScratch();
  ~DeriveScratch();
  DeriveScratch(DeriveScratch&&) noexcept;
  DeriveScratch& operator=(DeriveScratch&&) noexcept;

 private:
  friend void deriveStep(const Grammar&, const LString&, LString&, DeriveContext&, DeriveScratch&);
  friend void emitAxiom(const Grammar&, LString&, DeriveContext&);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Rewrites `in` into `out` (overwritten). Throws Error naming the grammar, the place and the
// rule on run-time errors, and when the string would outgrow the limits.
void deriveStep(const Grammar& g, const LString& in, LString& out, DeriveContext& context, DeriveScratch& scratch);

// The axiom (after Start:), decomposed and cut, into `out`.
void emitAxiom(const Grammar& g, LString& out, DeriveContext& context);

// Removes every % with the rest of its branch; a branch whose first module is % goes whole,
// brackets included.
void applyCuts(const Grammar& g, LString& s);

// match[i] = index of the bracket matching the bracket at i (unmatched: -1 for ], size() for [).
void matchBrackets(const Grammar& g, const LString& s, std::vector<int32_t>& match);

// Runs a Start/StartEach/EndEach/End block (`name`) on the globals. Errors name its place.
void runBlock(const Grammar& g, const Program& block, const char* name, double* globals, const RandomKey& key);

// Error for a failure inside a rule (production, decomposition or interpretation rule).
Error ruleError(const Grammar& g, const Production& p, const EvalFailure& f, const std::string& where);

}  // namespace tendril::lsystem
