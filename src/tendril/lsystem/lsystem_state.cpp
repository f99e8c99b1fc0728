// Saving and restoring an L-system's derivation exactly (sessions, undo).
#include "tendril/lsystem/lsystem.h"

#include <fmt/format.h>

namespace tendril::lsystem {

namespace {

constexpr uint32_t kLSystemTag = 0x53594c32;  // "2LYS" (2: the wind of every unit)

}  // namespace

// The grammar, seed, plant id, limits and start come from the options the LSystem was made
// with; the scratch buffers (next_, scratch_) are rewritten by every step.
void LSystem::saveState(ArchiveWriter& out) const {
  out.tag(kLSystemTag);
  out.u32(step_);
  out.u32(context_.step);
  out.value(int32_t(derivationLength_));
  out.boolean(answered_);
  out.vector(globals_);
  out.vector(current_.ids);
  out.vector(current_.paramStart);
  out.vector(current_.params);
  out.vector(current_.birth);
  // Growth-Flow: the wind of every derivation step so far.
  out.vector(wind_.sums());
  out.vector(wind_.activeCounts());
  out.vector(wind_.tornCounts());
  out.vector(wind_.winds());
}

void LSystem::loadState(ArchiveReader& in) {
  in.tag(kLSystemTag, "an L-system");
  step_ = in.u32();
  context_.step = in.u32();
  derivationLength_ = in.value<int32_t>();
  answered_ = in.boolean();
  const size_t globalsAt = in.position();
  in.vector(globals_);
  if (globals_.size() != grammar_->globalInit.size())
    in.fail(globalsAt, fmt::format("the saved L-system has {} global variables, its grammar {}", globals_.size(),
                                   grammar_->globalInit.size()));
  context_.globals = globals_.data();
  in.vector(current_.ids);
  in.vector(current_.paramStart);
  in.vector(current_.params);
  in.vector(current_.birth);
  const LString& s = current_;
  if (s.paramStart.size() != s.ids.size() + 1 || s.birth.size() != s.ids.size() || s.paramStart.front() != 0 ||
      s.paramStart.back() != s.params.size())
    in.fail("the saved L-system string is inconsistent");
  for (size_t i = 0; i < s.ids.size(); ++i)
    if (s.ids[i] >= grammar_->modules.size() || s.paramStart[i] > s.paramStart[i + 1])
      in.fail(fmt::format("module {} of the saved L-system string is not one of its grammar", i));
  const size_t windAt = in.position();
  auto sums = in.vector<plant::GrowthFlowHistory::Sums>();
  auto active = in.vector<uint32_t>();
  auto torn = in.vector<uint32_t>();
  auto winds = in.vector<Vec3>();
  if (sums.empty() || sums.size() != active.size() || sums.size() != torn.size() || sums.size() != winds.size())
    in.fail(windAt, "the saved L-system's wind history is inconsistent");
  wind_.restore(std::move(sums), std::move(active), std::move(torn), std::move(winds));
}

}  // namespace tendril::lsystem
