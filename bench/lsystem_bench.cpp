// L-system throughput (docs/grammar.md): one derivation step and one interpretation (turtle to
// PlantModel) of strings of about 40 thousand to 5 million modules, for a bracketed plant
// (ABOP Fig. 1.24a), a parametric tree (Fig. 2.6), a context-sensitive plant (Fig. 1.31a) and a
// stochastic one (Fig. 1.27). Rates are modules per second of the string produced (derivation)
// or drawn (interpretation); "threads" is the worker limit (1 = one core). Results and the
// command that produced them: bench/README.md.
#include "tendril/core/parallel.h"
#include "tendril/lsystem/lsystem.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>

namespace tendril {
namespace {

struct Case {
  const char* file;
  int firstSteps;  // the smallest derivation benchmarked: the string after this many steps
};

const Case kCases[] = {
    {"abop-1.24a.ls", 6},            // F -> F[+F]F[-F]F: x5 per step
    {"abop-2.6-monopodial.ls", 14},  // parametric, three productions
    {"abop-1.31a-context.ls", 60},   // context-sensitive with ignore:
    {"abop-1.27-stochastic.ls", 7},  // three stochastic productions
};

std::shared_ptr<const lsystem::Grammar> grammar(const char* file) {
  static std::map<std::string, std::shared_ptr<const lsystem::Grammar>> cache;
  auto& g = cache[file];
  if (!g) g = lsystem::loadGrammarFile(std::filesystem::path(TENDRIL_EXAMPLES_DIR) / "grammars" / file);
  return g;
}

// The string after `steps` steps (cached: setting it up is not what is measured).
const lsystem::LString& stringAfter(const char* file, int steps) {
  static std::map<std::pair<std::string, int>, std::unique_ptr<lsystem::LSystem>> cache;
  auto& ls = cache[{file, steps}];
  if (!ls) {
    lsystem::RunOptions o;
    o.derivationLength = steps;
    ls = std::make_unique<lsystem::LSystem>(grammar(file), o);
    ls->derive();
  }
  return ls->string();
}

// Arguments: case index, extra steps beyond the case's first, threads.
void BM_Derive(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const int steps = c.firstSteps + int(state.range(1));
  setThreadCount(int(state.range(2)));
  auto g = grammar(c.file);
  const lsystem::LString& in = stringAfter(c.file, steps - 1);
  lsystem::LString out;
  lsystem::DeriveScratch scratch;
  lsystem::DeriveContext context;
  context.seed = g->seed;
  context.step = uint32_t(steps);
  context.limits = g->limits;
  std::vector<double> globals = g->globalInit;
  context.globals = globals.data();
  for (auto _ : state) {
    lsystem::deriveStep(*g, in, out, context, scratch);
    benchmark::DoNotOptimize(out.ids.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(out.size()));
  state.counters["modules"] = double(out.size());
  state.counters["input"] = double(in.size());
  state.SetLabel(c.file);
  setThreadCount(0);
}

void BM_Interpret(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const int steps = c.firstSteps + int(state.range(1));
  setThreadCount(int(state.range(2)));
  auto g = grammar(c.file);
  const lsystem::LString& s = stringAfter(c.file, steps);
  lsystem::InterpretOptions o;
  o.seed = g->seed;
  o.step = uint32_t(steps);
  o.limits = g->limits;
  size_t nodes = 0;
  for (auto _ : state) {
    plant::PlantModel p = lsystem::interpret(*g, s, o, g->globalInit.data());
    nodes = p.nodeCount();
    benchmark::DoNotOptimize(p.position.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(s.size()));
  state.counters["modules"] = double(s.size());
  state.counters["nodes"] = double(nodes);
  state.SetLabel(c.file);
  setThreadCount(0);
}

void derivationArgs(benchmark::internal::Benchmark* b) {
  for (int threads : {1, 0})
    for (int64_t c = 0; c < int64_t(std::size(kCases)); ++c)
      for (int64_t extra = 0; extra < 3; ++extra) b->Args({c, extra, threads});
}

BENCHMARK(BM_Derive)->Apply(derivationArgs)->ArgNames({"grammar", "step", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Interpret)->Apply(derivationArgs)->ArgNames({"grammar", "step", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace tendril
