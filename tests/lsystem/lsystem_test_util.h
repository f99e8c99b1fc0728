// Helpers for the L-system tests: compile grammar text, derive it, read the string back.
#pragma once

#include "support/test_paths.h"
#include "tendril/lsystem/lsystem.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace tendril::lsystem::test {

inline RunOptions steps(int n, std::optional<uint64_t> seed = std::nullopt) {
  RunOptions o;
  o.derivationLength = n;
  o.seed = seed;
  return o;
}
inline RunOptions seeded(uint64_t seed) {
  RunOptions o;
  o.seed = seed;
  return o;
}
inline RunOptions stepTime(float seconds) {
  RunOptions o;
  o.stepTime = seconds;
  return o;
}
inline CompileOptions defines(std::vector<std::pair<std::string, double>> values) {
  CompileOptions o;
  o.defines = std::move(values);
  return o;
}

inline std::shared_ptr<const Grammar> compile(const std::string& text, const CompileOptions& options = {}) {
  return compileGrammar(text, "test.ls", options);
}

// The string after `steps` derivation steps (default: the grammar's derivation length).
inline std::string derived(const std::string& text, int steps = -1, uint64_t seed = 0) {
  RunOptions o;
  if (steps >= 0) o.derivationLength = steps;
  o.seed = seed;
  LSystem ls(compile(text), o);
  ls.derive();
  return ls.text();
}

// The error message of compiling (and deriving) `text`; "" when there is none.
inline std::string errorOf(const std::string& text, int steps = -1) {
  try {
    RunOptions o;
    if (steps >= 0) o.derivationLength = steps;
    LSystem ls(compile(text), o);
    ls.derive();
    ls.interpret();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

inline size_t countOf(const LSystem& ls, const std::string& name) {
  size_t n = 0;
  for (ModuleId id : ls.string().ids) n += ls.grammar().module(id).name == name;
  return n;
}

inline std::filesystem::path grammarPath(const std::string& file) {
  return tendril::test::sourceDir() / "examples" / "grammars" / file;
}

}  // namespace tendril::lsystem::test
