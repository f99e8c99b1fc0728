#include "tendril/lsystem/program.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace tendril::lsystem {

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

const FnInfo kFunctions[] = {
    {"sin", 1, 1, false},   {"cos", 1, 1, false},     {"tan", 1, 1, false},   {"asin", 1, 1, false},
    {"acos", 1, 1, false},  {"atan", 1, 1, false},    {"atan2", 2, 2, false}, {"sqrt", 1, 1, false},
    {"exp", 1, 1, false},   {"log", 1, 1, false},     {"log10", 1, 1, false}, {"pow", 2, 2, false},
    {"abs", 1, 1, false},   {"floor", 1, 1, false},   {"ceil", 1, 1, false},  {"round", 1, 1, false},
    {"trunc", 1, 1, false}, {"sign", 1, 1, false},    {"min", 2, 8, false},   {"max", 2, 8, false},
    {"clamp", 3, 3, false}, {"fmod", 2, 2, false},    {"norm", 1, 8, false},  {"dot", 2, 8, false},
    {"ran", 1, 1, true},    {"uniform", 2, 2, true},  {"nran", 2, 2, true},
};
static_assert(sizeof(kFunctions) / sizeof(kFunctions[0]) == size_t(Fn::Count));

[[noreturn]] void fail(uint32_t loc, std::string message) { throw EvalFailure{loc, std::move(message)}; }

double finite(double v, uint32_t loc, const char* what) {
  if (!std::isfinite(v)) fail(loc, fmt::format("{} is not a finite number", what));
  return v;
}

// The result of a function call, which must be finite.
double finiteCall(double v, uint32_t loc, const char* fn, const double* x, int n) {
  if (std::isfinite(v)) return v;
  std::string args;
  for (int i = 0; i < n; ++i) args += fmt::format("{}{:g}", i ? ", " : "", x[i]);
  fail(loc, fmt::format("{}({}) is not a finite number", fn, args));
}

}  // namespace

const FnInfo& fnInfo(Fn f) { return kFunctions[size_t(f)]; }

double callFunction(Fn f, const double* x, int n, LazyRng* rng, uint32_t loc) {
  switch (f) {
    case Fn::Sin: return std::sin(x[0] * kDegToRad);
    case Fn::Cos: return std::cos(x[0] * kDegToRad);
    case Fn::Tan: return finiteCall(std::tan(x[0] * kDegToRad), loc, "tan", x, n);
    case Fn::Asin:
      if (!(std::abs(x[0]) <= 1.0)) fail(loc, fmt::format("asin({:g}): the argument must lie in [-1, 1]", x[0]));
      return std::asin(x[0]) * kRadToDeg;
    case Fn::Acos:
      if (!(std::abs(x[0]) <= 1.0)) fail(loc, fmt::format("acos({:g}): the argument must lie in [-1, 1]", x[0]));
      return std::acos(x[0]) * kRadToDeg;
    case Fn::Atan: return std::atan(x[0]) * kRadToDeg;
    case Fn::Atan2: return std::atan2(x[0], x[1]) * kRadToDeg;
    case Fn::Sqrt:
      if (!(x[0] >= 0.0)) fail(loc, fmt::format("sqrt({:g}): square root of a negative number", x[0]));
      return std::sqrt(x[0]);
    case Fn::Exp: return finiteCall(std::exp(x[0]), loc, "exp", x, n);
    case Fn::Log:
      if (!(x[0] > 0.0)) fail(loc, fmt::format("log({:g}): logarithm of a number <= 0", x[0]));
      return std::log(x[0]);
    case Fn::Log10:
      if (!(x[0] > 0.0)) fail(loc, fmt::format("log10({:g}): logarithm of a number <= 0", x[0]));
      return std::log10(x[0]);
    case Fn::Pow: return finiteCall(std::pow(x[0], x[1]), loc, "pow", x, n);
    case Fn::Abs: return std::abs(x[0]);
    case Fn::Floor: return std::floor(x[0]);
    case Fn::Ceil: return std::ceil(x[0]);
    case Fn::Round: return std::round(x[0]);
    case Fn::Trunc: return std::trunc(x[0]);
    case Fn::Sign: return x[0] > 0.0 ? 1.0 : (x[0] < 0.0 ? -1.0 : 0.0);
    case Fn::Min: return *std::min_element(x, x + n);
    case Fn::Max: return *std::max_element(x, x + n);
    case Fn::Clamp: return std::min(std::max(x[0], x[1]), x[2]);
    case Fn::Fmod:
      if (x[1] == 0.0) fail(loc, "fmod by zero");
      return std::fmod(x[0], x[1]);
    case Fn::Norm: {
      double s = 0.0;
      for (int i = 0; i < n; ++i) s += x[i] * x[i];
      return std::sqrt(s);
    }
    case Fn::Dot: {
      if (n % 2 != 0) fail(loc, fmt::format("dot() takes two vectors of the same size, got {} numbers", n));
      double s = 0.0;
      for (int i = 0; i < n / 2; ++i) s += x[i] * x[i + n / 2];
      return s;
    }
    case Fn::Ran: return x[0] * double(rng->get().uniform());
    case Fn::Uniform: return x[0] + (x[1] - x[0]) * double(rng->get().uniform());
    case Fn::Nran: return x[0] + x[1] * double(rng->get().normal());
    case Fn::Count: break;
  }
  fail(loc, "unknown function");
}

double run(const Program& program, const RunContext& c) {
  const Instr* code = program.code.data();
  double* stack = c.stack;
  int sp = 0;  // number of values on the stack
  for (size_t pc = 0;;) {
    const Instr& in = code[pc++];
    switch (in.op) {
      case Op::Const: stack[sp++] = in.value; break;
      case Op::Load: stack[sp++] = c.slots[in.b]; break;
      case Op::Store: c.slots[in.b] = stack[--sp]; break;
      case Op::LoadGlobal: stack[sp++] = c.globals[in.b]; break;
      case Op::StoreGlobal:
        c.globals[in.b] = finite(stack[--sp], in.loc, "the value assigned");
        break;
      case Op::Neg: stack[sp - 1] = -stack[sp - 1]; break;
      case Op::Not: stack[sp - 1] = stack[sp - 1] == 0.0 ? 1.0 : 0.0; break;
      case Op::Add: --sp; stack[sp - 1] += stack[sp]; break;
      case Op::Sub: --sp; stack[sp - 1] -= stack[sp]; break;
      case Op::Mul: --sp; stack[sp - 1] *= stack[sp]; break;
      case Op::Div:
        --sp;
        if (stack[sp] == 0.0) fail(in.loc, "division by zero");
        stack[sp - 1] /= stack[sp];
        break;
      case Op::Mod:
        --sp;
        if (stack[sp] == 0.0) fail(in.loc, "modulo by zero");
        stack[sp - 1] = std::fmod(stack[sp - 1], stack[sp]);
        break;
      case Op::Pow:
        --sp;
        stack[sp - 1] = finite(std::pow(stack[sp - 1], stack[sp]), in.loc, "the power");
        break;
      case Op::Lt: --sp; stack[sp - 1] = stack[sp - 1] < stack[sp] ? 1.0 : 0.0; break;
      case Op::Le: --sp; stack[sp - 1] = stack[sp - 1] <= stack[sp] ? 1.0 : 0.0; break;
      case Op::Gt: --sp; stack[sp - 1] = stack[sp - 1] > stack[sp] ? 1.0 : 0.0; break;
      case Op::Ge: --sp; stack[sp - 1] = stack[sp - 1] >= stack[sp] ? 1.0 : 0.0; break;
      case Op::Eq: --sp; stack[sp - 1] = stack[sp - 1] == stack[sp] ? 1.0 : 0.0; break;
      case Op::Ne: --sp; stack[sp - 1] = stack[sp - 1] != stack[sp] ? 1.0 : 0.0; break;
      case Op::Jump: pc = in.b; break;
      case Op::JumpIfZero:
        if (stack[--sp] == 0.0) pc = in.b;
        break;
      case Op::Call: {
        sp -= in.b;
        stack[sp] = callFunction(Fn(in.a), stack + sp, in.b, c.rng, in.loc);
        ++sp;
        break;
      }
      case Op::Emit:
        sp -= in.a;
        c.sink->emit(ModuleId(in.b), stack + sp, in.a, in.loc);
        break;
      case Op::Return: return stack[--sp];
      case Op::Halt: return 0.0;
    }
  }
}

}  // namespace tendril::lsystem
