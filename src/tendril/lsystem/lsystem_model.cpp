#include "tendril/lsystem/lsystem_model.h"

#include "tendril/core/error.h"
#include "tendril/env/seed_check.h"
#include "tendril/lsystem/grammar_files.h"
#include "tendril/lsystem/lsystem.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace tendril::lsystem {

namespace {

// How near a support must be to a grammar that asks the environment, and how far it grows
// without one, for the diagnostics: seed 003's ivy's (its REACH of 0.08 m, MAXU of 6 segments
// of 0.04 m). A grammar's own values are expressions in it that the gauge does not evaluate.
constexpr float kQueryingSupportReach = 0.08f;
constexpr float kQueryingUnsupportedRun = 0.24f;

bool asksEnvironment(const Grammar& g) {
  for (const ModuleInfo& m : g.modules)
    if (m.op == TurtleOp::QueryEnvironment) return true;
  return false;
}

class LSystemPlantSystem final : public models::PlantSystem, public models::GrowthGauge {
 public:
  explicit LSystemPlantSystem(const models::SystemContext& c) : context_(c) {}

  void addPlant(const models::PlantSpec& spec, const env::Environment& env) override {
    env::checkSeedPosition(env, spec.position, spec.direction);
    plants_.push_back(start(spec, plants_.size(), env));
    names_.push_back(spec.name);
    growthFlow_.push_back(spec.paramsAs<LSystemParams>()->growthFlow);
    lastGrowth_.push_back(0);
    segments_.push_back(plants_.back()->segmentModules());
  }

  // A new grammar (or derivation length, placement...) for a growing plant: derived afresh
  // with the plant's own random keys for as many steps as the plant had taken (fewer when the
  // new derivation is shorter), each step asking the environment as it is now.
  void regrow(size_t plant, const models::PlantSpec& spec, const env::Environment& env) override {
    const uint32_t steps = plants_.at(plant)->stepCount();
    std::unique_ptr<LSystem> ls = start(spec, plant, env);
    try {
      while (ls->stepCount() < steps && !ls->finished()) ls->step(&env);
    } catch (const Error& e) {
      throw Error("", "/grammar", e.what());
    }
    plants_[plant] = std::move(ls);
    names_[plant] = spec.name;
    growthFlow_[plant] = spec.paramsAs<LSystemParams>()->growthFlow;
    lastGrowth_[plant] = plants_[plant]->stepCount();
    segments_[plant] = plants_[plant]->segmentModules();
  }

  void step(const env::Environment& env) override {
    for (size_t i = 0; i < plants_.size(); ++i) {
      LSystem& p = *plants_[i];
      if (p.finished()) continue;
      p.step(&env);
      const size_t now = p.segmentModules();  // one pass over the string a step
      if (now > segments_[i]) lastGrowth_[i] = p.stepCount();
      segments_[i] = now;
    }
  }

  bool finished() const override {
    for (const auto& p : plants_)
      if (!p->finished()) return false;
    return true;
  }

  size_t plantCount() const override { return plants_.size(); }
  const LSystem& derivation(size_t plant) const { return *plants_.at(plant); }

  plant::PlantModel snapshot(size_t plant) const override {
    plant::PlantModel m = plants_.at(plant)->interpret();
    m.name = names_[plant];
    return m;
  }

  plant::GrowthFlowSpecies growthFlow(size_t plant) const override { return growthFlow_.at(plant); }

  size_t segmentCount() const override {
    size_t n = 0;
    for (const auto& p : plants_) n += p->segmentModules();
    return n;
  }

  void saveState(ArchiveWriter& out) const override {
    out.u64(plants_.size());
    for (const auto& p : plants_) p->saveState(out);
  }
  void loadState(ArchiveReader& in) override {
    const size_t at = in.position();
    if (in.u64() != plants_.size()) in.fail(at, "the saved L-system plants differ from the session's");
    for (auto& p : plants_) p->loadState(in);
    // When they last grew is not saved: judged from now on.
    for (size_t i = 0; i < plants_.size(); ++i) {
      lastGrowth_[i] = plants_[i]->stepCount();
      segments_[i] = plants_[i]->segmentModules();
    }
  }

  // A grammar that asks the environment (?E) can be stopped by it (a climber with nothing to
  // climb, a shoot boxed in); one that does not grows as written anywhere. What such a grammar
  // would grow unhindered is not known (in an empty world a climber's grammar stops at once),
  // so the diagnostics judge it by when it stopped: its string still being derived, but no
  // segment added for kStallSteps steps.
  static constexpr uint32_t kStallSteps = 10;
  const models::GrowthGauge* growthGauge() const override { return this; }
  Reading growthReading(size_t plant) const override {
    const LSystem& ls = *plants_.at(plant);
    Reading r;
    r.unit = "segments";
    r.grown = double(ls.segmentModules());
    r.steps = ls.stepCount();
    r.lastGrowth = std::min(lastGrowth_.at(plant), r.steps);
    const bool asks = asksEnvironment(ls.grammar());
    r.complete = ls.finished() || !asks;
    r.growing = !ls.finished() && r.steps - r.lastGrowth < kStallSteps;
    // Grammars that ask the environment mostly climb: support within this reach of the seed.
    if (asks) {
      r.supportReach = kQueryingSupportReach;
      r.unsupportedRun = kQueryingUnsupportedRun;
    }
    return r;
  }
  double unhinderedGrowth(size_t, uint32_t) const override { return 0.0; }

 private:
  std::unique_ptr<LSystem> start(const models::PlantSpec& spec, size_t id, const env::Environment& env) const {
    const auto* params = spec.paramsAs<LSystemParams>();
    if (!params || !params->grammar) throw Error("", "/grammar", "the plant has no grammar");
    RunOptions o;
    o.seed = spec.seed ^ mix64(context_.sceneSeed);
    o.plant = id;
    o.derivationLength = params->derivationLength;
    o.start.position = spec.position;
    o.start.heading = spec.direction;
    o.stepTime = context_.stepTime;
    o.growthFlow = params->growthFlow;
    try {
      auto ls = std::make_unique<LSystem>(params->grammar, o);
      ls->answerQueries(&env);
      return ls;
    } catch (const Error& e) {
      // Start: or the axiom failed: the Session names the scene plant; keep the grammar's place.
      throw Error("", "/grammar", e.what());
    }
  }

  models::SystemContext context_;
  std::vector<std::unique_ptr<LSystem>> plants_;
  std::vector<std::string> names_;
  std::vector<plant::GrowthFlowSpecies> growthFlow_;
  std::vector<uint32_t> lastGrowth_;  // per plant: the step in which its segment count last rose
  std::vector<size_t> segments_;      // per plant: its segment count after its last step
};

std::shared_ptr<const models::ModelParams> readLSystemPlant(JsonObject& o, const std::filesystem::path& baseDir) {
  auto params = std::make_shared<LSystemParams>();
  if (!o.has("grammar") && !o.has("grammar_text"))
    throw o.error("grammar", "is required: a built-in grammar name (e.g. \"japanese-ivy\") or a path to a .ls file");
  const std::string ref = o.has("grammar") ? o.requiredString("grammar") : std::string();
  // "grammar_text": the grammar itself (an edited grammar, e.g. from the studio); "grammar"
  // then only names it and places its relative textures.
  const bool inline_ = o.has("grammar_text");
  const std::string text = inline_ ? o.requiredString("grammar_text") : std::string();
  auto load = [&](const CompileOptions& options) {
    if (!inline_) return loadGrammar(ref, baseDir, options, o.source(), o.pointerTo("grammar"));
    CompileOptions c = options;
    std::string name = o.source() + " " + o.pointerTo("grammar_text");
    if (!ref.empty()) {
      // The named grammar's directory and name, without needing its file any more.
      const bool isPath = ref.find('/') != std::string::npos || ref.ends_with(".ls");
      const std::filesystem::path p = std::filesystem::path(ref).is_absolute() ? std::filesystem::path(ref) : baseDir / ref;
      c.dir = isPath ? p.lexically_normal().parent_path() : std::filesystem::path(TENDRIL_EXAMPLES_DIR) / "grammars";
      name = (isPath ? p.lexically_normal().string() : ref) + " (edited)";
    } else {
      c.dir = baseDir;
    }
    return compileGrammar(text, name, c);
  };
  CompileOptions options;
  if (const Json* d = o.find("define")) {
    if (!d->is_object())
      throw o.error("define", "expected an object of define: constants and numbers, got " + describeJson(*d));
    for (auto it = d->begin(); it != d->end(); ++it) {
      std::string ptr = o.pointerTo("define") + "/" + jsonPointerEscape(it.key());
      if (!it.value().is_number()) throw Error(o.source(), ptr, "expected a number, got " + describeJson(it.value()));
      double v = it.value().get<double>();
      if (!std::isfinite(v)) throw Error(o.source(), ptr, "is not a finite number");
      options.defines.emplace_back(it.key(), v);
    }
  }
  std::shared_ptr<const Grammar> grammar = load({});
  if (!options.defines.empty()) {
    // Unknown names are reported at the scene key, with the grammar's constants listed.
    for (const auto& [name, value] : options.defines) {
      bool known = false;
      std::string list;
      for (const auto& [n, v] : grammar->defines) {
        known |= n == name;
        list += (list.empty() ? "" : ", ") + n;
      }
      if (!known)
        throw Error(o.source(), o.pointerTo("define") + "/" + jsonPointerEscape(name),
                    fmt::format("grammar {} has no define: constant \"{}\" (its constants: {})", grammar->source, name,
                                list.empty() ? "none" : list));
    }
    grammar = load(options);
  }
  params->grammar = std::move(grammar);
  int64_t length = o.integer("derivation_length", -1, 0, 10'000'000);
  if (length >= 0) params->derivationLength = int(length);
  if (auto g = o.optionalObject("growth_flow")) plant::readGrowthFlow(*g, params->growthFlow);
  return params;
}

}  // namespace

models::PlantSpec lsystemPlant(models::PlantSpec plant, std::shared_ptr<const Grammar> grammar,
                              std::optional<int> derivationLength) {
  auto params = std::make_shared<LSystemParams>();
  params->grammar = std::move(grammar);
  params->derivationLength = derivationLength;
  plant.model = "lsystem";
  plant.params = std::move(params);
  return plant;
}

const LSystem* derivationOf(const models::PlantSystem& system, size_t plant) {
  const auto* s = dynamic_cast<const LSystemPlantSystem*>(&system);
  return s ? &s->derivation(plant) : nullptr;
}

models::ModelType lsystemModelType() {
  return {"lsystem", "an L-system grammar drawn by a turtle (docs/grammar.md); ?E queries see the scene",
          readLSystemPlant, [](const models::SystemContext& c) { return std::make_unique<LSystemPlantSystem>(c); },
          "grammar"};
}

}  // namespace tendril::lsystem
