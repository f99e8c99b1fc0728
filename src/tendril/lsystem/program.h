// Compiled expressions, blocks and successors: a small stack bytecode run over doubles. The
// compiler (compiler.cpp) turns every condition, block, probability and successor of a grammar
// into one Program, so no text is looked at while deriving or interpreting.
//
// A Program reads and writes numbered slots (the bound module parameters and local variables
// of one production) and the grammar's global variables, and may emit modules into a sink
// (successors). Random functions draw from a keyed stream (core/random.h) made on first use,
// so a program that draws nothing pays nothing.
#pragma once

#include "tendril/core/random.h"
#include "tendril/lsystem/lstring.h"

#include <cstdint>
#include <string>
#include <vector>

namespace tendril::lsystem {

enum class Op : uint8_t {
  Const,        // push value
  Load,         // push slots[b]
  Store,        // slots[b] = pop
  LoadGlobal,   // push globals[b]
  StoreGlobal,  // globals[b] = pop
  Neg, Not,
  Add, Sub, Mul, Div, Mod, Pow,
  Lt, Le, Gt, Ge, Eq, Ne,
  Jump,         // to b
  JumpIfZero,   // pop; to b when it is 0
  Call,         // a = Fn, b = argument count
  Emit,         // module id b with a parameters popped from the stack
  Return,       // pop and return it
  Halt,         // return 0
};

// Built-in functions. Trigonometry is in degrees, as every angle in grammar files.
enum class Fn : uint8_t {
  Sin, Cos, Tan, Asin, Acos, Atan, Atan2,
  Sqrt, Exp, Log, Log10, Pow, Abs, Floor, Ceil, Round, Trunc, Sign,
  Min, Max, Clamp, Fmod, Norm, Dot,
  Ran, Uniform, Nran,  // random: [0, x), [a, b), normal(mean, sd)
  Count
};

struct FnInfo {
  const char* name;
  uint8_t minArgs, maxArgs;
  bool random;
};
const FnInfo& fnInfo(Fn f);

struct Instr {
  Op op = Op::Halt;
  uint8_t a = 0;
  uint32_t b = 0;    // slot, global, jump target, argument count or module id
  uint32_t loc = 0;  // index into Grammar::locations, for run-time errors
  double value = 0.0;
};

struct Program {
  std::vector<Instr> code;
  uint16_t maxStack = 0;  // deepest operand stack the code needs
  bool empty() const { return code.empty(); }
};

// A run-time error inside a program (division by zero, a non-finite parameter...). The caller
// turns it into an Error naming the grammar file, the place and the rule.
struct EvalFailure {
  uint32_t loc;
  std::string message;
};

// Where Emit puts modules. `loc` locates the emitting module in the grammar.
class EmitSink {
 public:
  virtual void emit(ModuleId id, const double* params, uint32_t count, uint32_t loc) = 0;

 protected:
  ~EmitSink() = default;
};

// A keyed random stream created on first use.
class LazyRng {
 public:
  explicit LazyRng(const RandomKey& key) : key_(key) {}
  Rng& get() {
    if (!made_) {
      rng_ = Rng(key_);
      made_ = true;
    }
    return rng_;
  }

 private:
  RandomKey key_;
  Rng rng_{uint64_t(0)};
  bool made_ = false;
};

struct RunContext {
  double* slots = nullptr;
  double* globals = nullptr;
  double* stack = nullptr;  // at least program.maxStack entries
  LazyRng* rng = nullptr;
  EmitSink* sink = nullptr;
};

// Runs a program; returns the value of Return (0 at Halt). Throws EvalFailure.
double run(const Program& program, const RunContext& context);

// Evaluates a pure function (no random ones) for constant folding; throws EvalFailure on a
// domain problem such as division by zero.
double callFunction(Fn f, const double* args, int count, LazyRng* rng, uint32_t loc);

}  // namespace tendril::lsystem
