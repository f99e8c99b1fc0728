#include "tendril/lsystem/lsystem.h"

#include "tendril/core/error.h"

#include <fmt/format.h>

namespace tendril::lsystem {

LSystem::LSystem(std::shared_ptr<const Grammar> grammar, const RunOptions& options)
    : grammar_(std::move(grammar)), options_(options) {
  const Grammar& g = *grammar_;
  context_.seed = options.seed.value_or(g.seed);
  context_.plant = options.plant;
  context_.limits = options.limits.value_or(g.limits);
  derivationLength_ = options.derivationLength.value_or(g.derivationLength);
  globals_ = g.globalInit;
  context_.globals = globals_.data();
  block(g.start, "Start", 0);
  context_.step = 0;
  emitAxiom(g, current_, context_);
  if (finished()) block(g.end, "End", 3);
}

LSystem::~LSystem() = default;
LSystem::LSystem(LSystem&& o) noexcept
    : grammar_(std::move(o.grammar_)),
      options_(std::move(o.options_)),
      context_(o.context_),
      derivationLength_(o.derivationLength_),
      step_(o.step_),
      globals_(std::move(o.globals_)),
      current_(std::move(o.current_)),
      next_(std::move(o.next_)),
      scratch_(std::move(o.scratch_)),
      answered_(o.answered_),
      wind_(std::move(o.wind_)) {
  context_.globals = globals_.data();
}
LSystem& LSystem::operator=(LSystem&& o) noexcept {
  grammar_ = std::move(o.grammar_);
  options_ = std::move(o.options_);
  context_ = o.context_;
  derivationLength_ = o.derivationLength_;
  step_ = o.step_;
  globals_ = std::move(o.globals_);
  current_ = std::move(o.current_);
  next_ = std::move(o.next_);
  scratch_ = std::move(o.scratch_);
  answered_ = o.answered_;
  wind_ = std::move(o.wind_);
  context_.globals = globals_.data();
  return *this;
}

void LSystem::block(const Program& p, const char* name, uint64_t which) {
  runBlock(*grammar_, p, name, globals_.data(),
           RandomKey{context_.seed, context_.plant, which, step_, kPurposeBlock});
}

InterpretOptions LSystem::interpretOptions() const {
  InterpretOptions o;
  o.start = options_.start;
  o.seed = context_.seed;
  o.plant = context_.plant;
  o.step = step_;
  o.stepTime = options_.stepTime;
  o.limits = context_.limits;
  o.wind = &wind_;
  o.growthFlow = &options_.growthFlow;
  return o;
}

void LSystem::answerQueries(const env::Environment* env) {
  fillQueries(*grammar_, current_, interpretOptions(), globals_.data(), env);
  answered_ = true;
}

void LSystem::step(const env::Environment* env) {
  if (finished()) return;
  const Grammar& g = *grammar_;
  // Productions read the answers for the string they rewrite (open L-systems).
  if (g.hasQueries && !answered_) answerQueries(env);
  ++step_;
  context_.step = step_;
  // Growth-Flow: this step is one unit of growth time in the wind at the plant's base.
  Vec3 wind = Vec3::Zero();
  if (env && !env->windField().settings().calm())
    wind = env->wind(options_.start.position, float(step_ - 1) * options_.stepTime);
  wind_.record(wind, options_.growthFlow);
  block(g.startEach, "StartEach", 1);
  deriveStep(g, current_, next_, context_, scratch_);
  current_.swap(next_);
  answered_ = false;
  if (g.hasQueries) answerQueries(env);
  block(g.endEach, "EndEach", 2);
  if (finished()) block(g.end, "End", 3);
}

void LSystem::derive(const env::Environment* env) {
  while (!finished()) step(env);
}

double LSystem::global(std::string_view name) const {
  int i = grammar_->globalIndex(name);
  if (i < 0) throw Error(grammar_->source, "", fmt::format("the grammar has no global variable \"{}\"", name));
  return globals_[size_t(i)];
}

size_t LSystem::segmentModules() const {
  const Grammar& g = *grammar_;
  size_t n = 0;
  for (ModuleId id : current_.ids) n += g.modules[id].op == TurtleOp::Forward;
  return n;
}

plant::PlantModel LSystem::interpret() const {
  return lsystem::interpret(*grammar_, current_, interpretOptions(), globals_.data());
}

}  // namespace tendril::lsystem
