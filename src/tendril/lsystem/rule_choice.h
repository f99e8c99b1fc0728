// Which rule rewrites a module, shared by derivation (productions, decomposition) and
// interpretation: the first candidate that applies — or, when the first applicable candidate
// belongs to a stochastic group (ABOP §1.7), one member of the group drawn with probability
// proportional to its weight among the members that apply.
#pragma once

#include "tendril/lsystem/grammar.h"

#include <algorithm>
#include <vector>

namespace tendril::lsystem {

// The most members of one stochastic group among the candidates of any module in a section
// (the frames a choice needs besides the plain one).
inline size_t largestGroup(const Grammar& g, Section s) {
  size_t best = 0;
  std::vector<size_t> count;
  for (const std::vector<uint32_t>& list : g.candidates[size_t(s)]) {
    count.clear();
    for (uint32_t i : list) {
      int32_t group = g.productions[i].group;
      if (group < 0) continue;
      if (count.size() <= size_t(group)) count.resize(size_t(group) + 1, 0);
      best = std::max(best, ++count[size_t(group)]);
    }
  }
  return best;
}

// applies(p, slot) binds p's parameters into frame `slot` (0 for a plain production, 1 + i for
// the i-th member of a group) and evaluates its condition; weigh(p, slot) returns its weight
// (>= 0). Returns the chosen rule (nullptr: none applies) and its frame slot in *slotOut.
template <class Applies, class Weigh>
const Production* chooseRule(const Grammar& g, const std::vector<uint32_t>& list, LazyRng& rng,
                             std::vector<const Production*>& members, std::vector<double>& weights,
                             const Applies& applies, const Weigh& weigh, size_t* slotOut) {
  int32_t doneGroup = -1;
  for (size_t k = 0; k < list.size(); ++k) {
    const Production& p = g.productions[list[k]];
    if (p.group < 0) {
      if (applies(p, size_t(0))) {
        *slotOut = 0;
        return &p;
      }
      continue;
    }
    if (p.group == doneGroup) continue;
    doneGroup = p.group;
    members.clear();
    weights.clear();
    double total = 0.0;
    for (size_t m = k; m < list.size(); ++m) {
      const Production& q = g.productions[list[m]];
      if (q.group != p.group) continue;
      size_t slot = members.size() + 1;
      if (!applies(q, slot)) continue;
      double w = weigh(q, slot);
      members.push_back(&q);
      weights.push_back(w);
      total += w;
    }
    if (total <= 0.0) continue;  // no member applies, or all weigh 0: try later productions
    double r = double(rng.get().uniform()) * total;
    size_t pick = 0;
    double acc = weights[0];
    while (pick + 1 < members.size() && r >= acc) acc += weights[++pick];
    while (pick > 0 && weights[pick] == 0.0) --pick;  // rounding carried r past the last positive weight
    *slotOut = pick + 1;
    return members[pick];
  }
  return nullptr;
}

}  // namespace tendril::lsystem
