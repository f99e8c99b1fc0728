#include "tendril/lsystem/grammar.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace tendril::lsystem {

std::pair<int, int> queryArity(QueryKind kind) {
  switch (kind) {
    case QueryKind::Surface:
    case QueryKind::Hit: return {2, 6};
    case QueryKind::Light: return {1, 5};
    case QueryKind::Attract: return {1, 5};
    case QueryKind::Facing: return {3, 7};
  }
  return {1, 6};
}

std::string queryProblem(double kind, int count) {
  if (!(kind >= 1.0 && kind <= double(kQueryKinds) && kind == std::floor(kind)))
    return fmt::format("unknown ?E query kind {:g} (SURFACE, HIT, LIGHT, ATTRACT or FACING)", kind);
  auto [lo, hi] = queryArity(QueryKind(int(kind)));
  if (count >= lo && count <= hi) return "";
  const char* names[] = {"", "SURFACE", "HIT", "LIGHT", "ATTRACT", "FACING"};
  return fmt::format("?E({}, ...) takes {} to {} parameters, {} here", names[int(kind)], lo, hi, count);
}

bool Grammar::hasRules(Section s) const {
  return std::any_of(productions.begin(), productions.end(), [&](const Production& p) { return p.section == s; });
}

int Grammar::globalIndex(std::string_view n) const {
  auto it = std::find(globalNames.begin(), globalNames.end(), n);
  return it == globalNames.end() ? -1 : int(it - globalNames.begin());
}

std::string Grammar::location(uint32_t loc) const {
  if (loc == 0 || loc >= locations.size()) return "";
  return fmt::format("{}:{}", locations[loc].line, locations[loc].col);
}

std::string formatModule(const Grammar& g, ModuleId id, const float* params, uint32_t count) {
  std::string s = g.modules[id].name;
  if (count == 0) return s;
  s += '(';
  for (uint32_t i = 0; i < count; ++i) s += fmt::format("{}{:g}", i ? ", " : "", params[i]);
  s += ')';
  return s;
}

std::string formatString(const Grammar& g, const LString& str, size_t maxModules) {
  std::string s;
  size_t n = std::min(str.size(), maxModules);
  for (size_t i = 0; i < n; ++i) {
    const std::string& name = g.modules[str.ids[i]].name;
    // Multi-character names are separated by spaces so that the text reads back the same.
    if (i > 0 && (name.size() > 1 || g.modules[str.ids[i - 1]].name.size() > 1)) s += ' ';
    s += formatModule(g, str.ids[i], str.paramsOf(i), str.paramCount(i));
  }
  if (n < str.size()) s += fmt::format(" ... ({} more modules)", str.size() - n);
  return s;
}

}  // namespace tendril::lsystem
