#include "tendril/lsystem/derivation.h"

#include "tendril/core/parallel.h"
#include "tendril/lsystem/rule_choice.h"

#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <optional>

namespace tendril::lsystem {

namespace {

// Modules per parallel task. Fixed, so that the work split — and with it which error is
// reported first — never depends on the thread count.
constexpr size_t kChunk = 16384;
// Emitted modules are counted against the shared limits in batches of this many.
constexpr size_t kBudgetBatch = 4096;

const char* sectionName(Section s) {
  switch (s) {
    case Section::Production: return "production";
    case Section::Decomposition: return "decomposition rule";
    case Section::Interpretation: return "interpretation rule";
  }
  return "rule";
}

// The string-length budget shared by all chunks of a step.
struct Budget {
  std::atomic<size_t> modules{0}, params{0};
  size_t maxModules = 0, maxParams = 0;
  bool exceeded() const { return modules.load() > maxModules || params.load() > maxParams; }
};

struct LimitExceeded {};

class Rewriter;

// Receives the modules a successor emits at one decomposition depth.
class LevelSink final : public EmitSink {
 public:
  LevelSink(Rewriter& r, int depth, uint64_t path) : r_(r), depth_(depth), path_(path) {}
  void emit(ModuleId id, const double* params, uint32_t count, uint32_t loc) override;

 private:
  Rewriter& r_;
  int depth_;
  uint64_t path_;
  uint32_t emitted_ = 0;
};

class Rewriter {
 public:
  Rewriter(const Grammar& g, const LString* in, const int32_t* brackets, const DeriveContext& c, LString& out,
           Budget& budget)
      : g_(g), in_(in), brackets_(brackets), c_(c), out_(out), budget_(budget) {
    levelFrames_ = size_t(g.maxFrame) * (g.maxGroup + 1) + 1;
    levelStack_ = size_t(g.maxStack) + 1;
    levels_.resize(size_t(g.maxDepth[size_t(Section::Decomposition)]) + 2);
  }

  ~Rewriter() { flushBudget(); }

  // Productions over input modules [begin, end).
  void derive(size_t begin, size_t end) {
    const LString& in = *in_;
    const auto& cands = g_.candidates[size_t(Section::Production)];
    size_t run = begin;  // start of the current run of modules copied unchanged
    for (size_t i = begin; i < end; ++i) {
      const std::vector<uint32_t>& list = cands[in.ids[i]];
      if (list.empty()) continue;
      LazyRng rng(RandomKey{c_.seed, c_.plant, i, c_.step, kPurposeProduction});
      double* frame = nullptr;
      const Production* p = select(list, in.paramsOf(i), int64_t(i), 0, rng, &frame);
      if (!p) continue;
      if (run < i) copy(run, i);
      run = i + 1;
      LevelSink sink(*this, 1, i);
      execute(*p, p->successor, frame, 0, rng, &sink, [&] { return where(i); });
    }
    if (run < end) copy(run, end);
  }

  // The axiom program, decomposed.
  void axiom(double* globals) {
    LazyRng rng(RandomKey{c_.seed, c_.plant, 0, 0, kPurposeAxiom});
    LevelSink sink(*this, 1, 0);
    RunContext rc;
    rc.globals = globals;
    rc.stack = stack(0);
    rc.rng = &rng;
    rc.sink = &sink;
    try {
      run(g_.axiom, rc);
    } catch (const EvalFailure& f) {
      throw Error(g_.source, g_.location(f.loc), f.message + " in the axiom");
    }
  }

  // A module emitted at decomposition depth `depth` (1 = straight from a production).
  void emitModule(ModuleId id, const double* params, uint32_t n, uint32_t loc, int depth, uint64_t path) {
    float f[256];
    for (uint32_t k = 0; k < n; ++k) {
      f[k] = float(params[k]);
      if (!std::isfinite(f[k]))
        throw EvalFailure{loc, fmt::format("parameter {} of {} is not a finite number ({:g})", k + 1,
                                           g_.modules[id].name, params[k])};
    }
    if (g_.modules[id].op == TurtleOp::QueryEnvironment)
      if (std::string problem = queryProblem(f[0], int(n)); !problem.empty()) throw EvalFailure{loc, problem};
    const auto& list = g_.candidates[size_t(Section::Decomposition)][id];
    if (!list.empty()) {
      LazyRng rng(RandomKey{c_.seed, c_.plant, path, c_.step, kPurposeDecomposition});
      double* frame = nullptr;
      const Production* p = select(list, f, -1, depth, rng, &frame);
      if (p) {
        if (depth > g_.maxDepth[size_t(Section::Decomposition)])
          throw Error(g_.source, fmt::format("{}:{}", p->pos.line, p->pos.col),
                      fmt::format("decomposition goes deeper than its maximum depth {} (rule `{}` still applies to "
                                  "{}); raise `maximum depth:` in the decomposition: section",
                                  g_.maxDepth[size_t(Section::Decomposition)], p->text,
                                  formatModule(g_, id, f, n)));
        LevelSink sink(*this, depth + 1, path);
        ModuleId mid = id;
        execute(*p, p->successor, frame, depth, rng, &sink,
                [&] { return fmt::format("decomposing {} in step {}", formatModule(g_, mid, f, n), c_.step); });
        return;
      }
    }
    push(id, f, n);
  }

 private:
  // Frames and operand stack of one decomposition depth (0: productions), made on first use.
  double* frames(int level) {
    std::vector<double>& m = levels_[size_t(level)];
    if (m.empty()) m.assign(levelFrames_ + levelStack_, 0.0);
    return m.data();
  }
  double* stack(int level) { return frames(level) + levelFrames_; }

  std::string where(size_t i) const {
    return fmt::format("rewriting module {}, {}, in step {}", i, formatModule(g_, in_->ids[i], in_->paramsOf(i),
                                                                               in_->paramCount(i)),
                       c_.step);
  }

  void copy(size_t from, size_t to) {
    out_.append(*in_, from, to);
    count(to - from, in_->paramStart[to] - in_->paramStart[from]);
  }

  void push(ModuleId id, const float* f, uint32_t n) {
    out_.push(id, f, n, c_.step);
    count(1, n);
  }

  void count(size_t modules, size_t params) {
    pendingModules_ += modules;
    pendingParams_ += params;
    if (pendingModules_ >= kBudgetBatch || pendingParams_ >= 4 * kBudgetBatch) {
      flushBudget();
      if (budget_.exceeded()) throw LimitExceeded{};
    }
  }

  void flushBudget() {
    budget_.modules += pendingModules_;
    budget_.params += pendingParams_;
    pendingModules_ = pendingParams_ = 0;
  }

  template <class Where>
  double execute(const Production& p, const Program& prog, double* frame, int level, LazyRng& rng, EmitSink* sink,
                 const Where& where) {
    RunContext rc;
    rc.slots = frame;
    rc.globals = c_.globals;
    rc.stack = stack(level);
    rc.rng = &rng;
    rc.sink = sink;
    try {
      return run(prog, rc);
    } catch (const EvalFailure& f) {
      throw ruleError(g_, p, f, where());
    }
  }

  bool matches(const PatternItem& it, ModuleId id) const {
    const ModuleInfo& m = g_.modules[id];
    return m.nameIndex == it.nameIndex && (it.arity < 0 || it.arity == m.arity);
  }

  void bind(const PatternItem& it, size_t j, double* frame) const {
    if (it.arity <= 0) return;
    const float* p = in_->paramsOf(j);
    for (int k = 0; k < it.arity; ++k) frame[it.slot + k] = p[k];
  }

  // ABOP §1.8: the left context is read toward the root: a sibling branch ([...] ending
  // just before) is skipped whole, and the [ that opens the branch leads to its parent.
  bool matchLeft(const Production& p, size_t i, double* frame) const {
    const LString& in = *in_;
    int64_t j = int64_t(i) - 1;
    for (size_t k = p.left.size(); k-- > 0;) {
      for (;;) {
        if (j < 0) return false;
        ModuleId id = in.ids[size_t(j)];
        if (id == g_.closeId) j = int64_t(brackets_[j]) - 1;
        else if (id == g_.openId || g_.ignored[id]) --j;
        else break;
      }
      if (!matches(p.left[k], in.ids[size_t(j)])) return false;
      bind(p.left[k], size_t(j), frame);
      --j;
    }
    return true;
  }

  // The right context is read toward the tips: branches the pattern does not name are
  // skipped, a [ in the pattern enters a branch (trying each sibling in turn), and the end of
  // the current branch ends the match.
  bool matchRight(const Production& p, size_t k, size_t end, size_t& j, double* frame) const {
    const LString& in = *in_;
    const size_t n = in.size();
    while (k < end) {
      const PatternItem& it = p.right[k];
      if (it.kind == PatternItem::Kind::Open) {
        const size_t close = size_t(it.partner);
        for (;;) {
          while (j < n && in.ids[j] != g_.openId && in.ids[j] != g_.closeId && g_.ignored[in.ids[j]]) ++j;
          if (j >= n || in.ids[j] != g_.openId) return false;
          size_t inner = j + 1;
          size_t after = size_t(brackets_[j]) + 1;
          if (matchRight(p, k + 1, close, inner, frame)) {
            j = after;
            k = close + 1;
            break;
          }
          j = after;
        }
        continue;
      }
      for (;;) {
        if (j >= n) return false;
        ModuleId id = in.ids[j];
        if (id == g_.openId) j = size_t(brackets_[j]) + 1;
        else if (id == g_.closeId) return false;
        else if (g_.ignored[id]) ++j;
        else break;
      }
      if (!matches(it, in.ids[j])) return false;
      bind(it, j, frame);
      ++j;
      ++k;
    }
    return true;
  }

  // Does production p apply? Binds its parameters into `frame` and runs its condition.
  bool applies(const Production& p, const float* pred, int64_t i, double* frame, int level, LazyRng& rng) {
    if (!p.left.empty() && !matchLeft(p, size_t(i), frame)) return false;
    if (!p.right.empty()) {
      size_t j = size_t(i) + 1;
      if (!matchRight(p, 0, p.right.size(), j, frame)) return false;
    }
    if (p.predArity > 0)
      for (int k = 0; k < p.predArity; ++k) frame[p.predSlot + k] = pred[k];
    for (uint16_t s = p.paramCount; s < p.frameSize; ++s) frame[s] = 0.0;  // locals start at 0
    if (p.match.empty()) return true;
    return execute(p, p.match, frame, level, rng, nullptr, [&] { return whereFor(i); }) != 0.0;
  }

  std::string whereFor(int64_t i) const {
    if (i >= 0) return where(size_t(i));
    return fmt::format("decomposing in step {}", c_.step);
  }

  // The rule that rewrites the module (rule_choice.h); `*frameOut` receives its parameters.
  const Production* select(const std::vector<uint32_t>& list, const float* pred, int64_t i, int level, LazyRng& rng,
                           double** frameOut) {
    double* base = frames(level);
    const size_t stride = g_.maxFrame;
    size_t slot = 0;
    const Production* p = chooseRule(
        g_, list, rng, members_, weights_,
        [&](const Production& q, size_t s) { return applies(q, pred, i, base + stride * s, level, rng); },
        [&](const Production& q, size_t s) {
          double w = execute(q, q.weight, base + stride * s, level, rng, nullptr, [&] { return whereFor(i); });
          if (!(w >= 0.0) || !std::isfinite(w))
            throw ruleError(g_, q, EvalFailure{0, fmt::format("probability {:g} is not a finite number >= 0", w)},
                            whereFor(i));
          return w;
        },
        &slot);
    *frameOut = base + stride * slot;
    return p;
  }

  friend class LevelSink;

  const Grammar& g_;
  const LString* in_;
  const int32_t* brackets_;
  const DeriveContext& c_;
  LString& out_;
  Budget& budget_;
  size_t levelFrames_ = 0, levelStack_ = 0;
  std::vector<std::vector<double>> levels_;
  std::vector<const Production*> members_;
  std::vector<double> weights_;
  size_t pendingModules_ = 0, pendingParams_ = 0;
};

void LevelSink::emit(ModuleId id, const double* params, uint32_t count, uint32_t loc) {
  r_.emitModule(id, params, count, loc, depth_, childPath(path_, emitted_++));
}

Error limitError(const Grammar& g, const Budget& b, uint32_t step) {
  if (b.modules.load() > b.maxModules)
    return Error(g.source, "",
                 fmt::format("step {} would make the string longer than {} modules (its limit); raise `max length:` "
                             "in the grammar, or derive fewer steps",
                             step, b.maxModules));
  return Error(g.source, "",
               fmt::format("step {} would make the string hold more than {} parameter values (its limit); raise "
                           "`max length:` in the grammar, or derive fewer steps",
                           step, b.maxParams));
}

}  // namespace

Error ruleError(const Grammar& g, const Production& p, const EvalFailure& f, const std::string& where) {
  std::string loc = g.location(f.loc);
  if (loc.empty()) loc = fmt::format("{}:{}", p.pos.line, p.pos.col);
  return Error(g.source, loc, fmt::format("{} in {} `{}` ({})", f.message, sectionName(p.section), p.text, where));
}

struct DeriveScratch::Impl {
  std::vector<LString> chunks;
  std::vector<int32_t> brackets;
};

DeriveScratch::DeriveScratch() : impl_(std::make_unique<Impl>()) {}
DeriveScratch::~DeriveScratch() = default;
DeriveScratch::DeriveScratch(DeriveScratch&&) noexcept = default;
DeriveScratch& DeriveScratch::operator=(DeriveScratch&&) noexcept = default;

void matchBrackets(const Grammar& g, const LString& s, std::vector<int32_t>& match) {
  match.assign(s.size(), 0);
  std::vector<int32_t> open;
  for (size_t i = 0; i < s.size(); ++i) {
    ModuleId id = s.ids[i];
    if (id == g.openId) {
      open.push_back(int32_t(i));
      match[i] = int32_t(s.size());
    } else if (id == g.closeId) {
      if (open.empty()) {
        match[i] = -1;
      } else {
        match[i] = open.back();
        match[size_t(open.back())] = int32_t(i);
        open.pop_back();
      }
    }
  }
}

void applyCuts(const Grammar& g, LString& s) {
  if (g.cutId == Grammar::kNoModule) return;
  const size_t n = s.size();
  size_t w = 0;
  uint32_t pw = 0;  // params written
  for (size_t r = 0; r < n; ++r) {
    ModuleId id = s.ids[r];
    if (id == g.cutId) {
      // The end of the branch: its closing ] (kept), or the end of the string.
      size_t q = r + 1;
      for (int depth = 0; q < n; ++q) {
        if (s.ids[q] == g.openId) ++depth;
        else if (s.ids[q] == g.closeId && depth-- == 0) break;
      }
      if (w > 0 && s.ids[w - 1] == g.openId && q < n) {
        --w;  // % opened the branch: the branch goes whole
        pw = s.paramStart[w];
        r = q;
      } else {
        r = q - 1;
      }
      continue;
    }
    uint32_t from = s.paramStart[r], count = s.paramStart[r + 1] - from;
    s.ids[w] = id;
    s.birth[w] = s.birth[r];
    s.paramStart[w] = pw;
    for (uint32_t k = 0; k < count; ++k) s.params[pw + k] = s.params[from + k];
    pw += count;
    ++w;
  }
  s.ids.resize(w);
  s.birth.resize(w);
  s.paramStart.resize(w + 1);
  s.paramStart[w] = pw;
  s.params.resize(pw);
}

void deriveStep(const Grammar& g, const LString& in, LString& out, DeriveContext& c, DeriveScratch& scratch) {
  DeriveScratch::Impl& sc = *scratch.impl_;
  const int32_t* brackets = nullptr;
  if (g.hasContext) {
    matchBrackets(g, in, sc.brackets);
    brackets = sc.brackets.data();
  }
  Budget budget;
  budget.maxModules = c.limits.maxModules;
  budget.maxParams = c.limits.maxParams;
  const size_t n = in.size();
  const size_t chunkSize = g.sequential ? std::max<size_t>(n, 1) : kChunk;
  const size_t chunks = std::max<size_t>(1, (n + chunkSize - 1) / chunkSize);
  if (sc.chunks.size() < chunks) sc.chunks.resize(chunks);
  struct Outcome {
    std::optional<Error> error;
    bool limit = false;
  };
  std::vector<Outcome> outcomes(chunks);
  auto work = [&](size_t k) {
    LString& o = sc.chunks[k];
    o.clear();
    size_t begin = k * chunkSize, end = std::min(n, begin + chunkSize);
    try {
      Rewriter r(g, &in, brackets, c, o, budget);
      r.derive(begin, end);
    } catch (const LimitExceeded&) {
      outcomes[k].limit = true;
    } catch (const Error& e) {
      outcomes[k].error = e;
    }
  };
  if (g.sequential || chunks == 1) {
    for (size_t k = 0; k < chunks; ++k) work(k);
  } else {
    parallelFor(0, chunks, work, 1);
  }
  // A limit error whenever the whole step outgrew the limits (that does not depend on which
  // chunk noticed it first); otherwise the error of the first chunk that had one.
  if (budget.exceeded()) throw limitError(g, budget, c.step);
  for (Outcome& o : outcomes)
    if (o.limit) throw limitError(g, budget, c.step);
  for (Outcome& o : outcomes)
    if (o.error) throw *o.error;

  if (chunks == 1) {
    out.swap(sc.chunks[0]);
  } else {
    std::vector<size_t> moduleBase(chunks + 1, 0), paramBase(chunks + 1, 0);
    for (size_t k = 0; k < chunks; ++k) {
      moduleBase[k + 1] = moduleBase[k] + sc.chunks[k].size();
      paramBase[k + 1] = paramBase[k] + sc.chunks[k].params.size();
    }
    if (paramBase[chunks] > UINT32_MAX) throw limitError(g, budget, c.step);
    out.ids.resize(moduleBase[chunks]);
    out.birth.resize(moduleBase[chunks]);
    out.params.resize(paramBase[chunks]);
    out.paramStart.resize(moduleBase[chunks] + 1);
    parallelFor(0, chunks, [&](size_t k) {
      const LString& s = sc.chunks[k];
      std::copy(s.ids.begin(), s.ids.end(), out.ids.begin() + moduleBase[k]);
      std::copy(s.birth.begin(), s.birth.end(), out.birth.begin() + moduleBase[k]);
      std::copy(s.params.begin(), s.params.end(), out.params.begin() + paramBase[k]);
      uint32_t pb = uint32_t(paramBase[k]);
      for (size_t m = 0; m < s.size(); ++m) out.paramStart[moduleBase[k] + m] = s.paramStart[m] + pb;
    }, 1);
    out.paramStart[moduleBase[chunks]] = uint32_t(paramBase[chunks]);
  }
  if (g.producesCut) applyCuts(g, out);
}

void emitAxiom(const Grammar& g, LString& out, DeriveContext& c) {
  out.clear();
  Budget budget;
  budget.maxModules = c.limits.maxModules;
  budget.maxParams = c.limits.maxParams;
  try {
    Rewriter r(g, nullptr, nullptr, c, out, budget);
    r.axiom(c.globals);
  } catch (const LimitExceeded&) {
    throw limitError(g, budget, 0);
  }
  if (budget.exceeded()) throw limitError(g, budget, 0);
  if (g.producesCut) applyCuts(g, out);
}

void runBlock(const Grammar& g, const Program& block, const char* name, double* globals, const RandomKey& key) {
  if (block.empty()) return;
  std::vector<double> stack(size_t(block.maxStack) + 1);
  LazyRng rng(key);
  RunContext rc;
  rc.globals = globals;
  rc.stack = stack.data();
  rc.rng = &rng;
  try {
    run(block, rc);
  } catch (const EvalFailure& f) {
    throw Error(g.source, g.location(f.loc), fmt::format("{} in the {} block", f.message, name));
  }
}

}  // namespace tendril::lsystem
