// libFuzzer target for the grammar language (docs/grammar.md). Any bytes are compiled; grammars
// that compile are derived for a few steps within small limits and drawn. Every problem in the
// input must be a tendril::Error — anything else (a crash, a hang, a leak, a sanitizer report,
// or a turtle drawing an invalid PlantModel) is a bug. Run with `make fuzz`.
#include "../fuzz_init.h"
#include "tendril/core/error.h"
#include "tendril/lsystem/lsystem.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace tendril;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  plant::PlantModel plant;
  try {
    std::shared_ptr<const lsystem::Grammar> g = lsystem::compileGrammar(text, "fuzz.ls");
    lsystem::RunOptions o;
    o.derivationLength = std::min(g->derivationLength, 6);
    lsystem::Limits limits;
    limits.maxModules = std::min<size_t>(g->limits.maxModules, 4000);
    limits.maxParams = lsystem::kParamsPerModule * limits.maxModules;
    o.limits = limits;
    lsystem::LSystem ls(g, o);
    ls.derive();  // an empty world answers the queries
    plant = ls.interpret();
    (void)ls.text(200);
  } catch (const Error& e) {
    (void)lsystem::renderDiagnostic(text, e);
    return 0;
  }
  try {
    plant::validate(plant, "fuzz.ls");
  } catch (const Error& e) {
    std::fprintf(stderr, "the turtle drew an invalid plant: %s\n", e.what());
    std::abort();
  }
  return 0;
}
