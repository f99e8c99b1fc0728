// Grammar text → syntax tree. Syntax errors are Error(source, "line:col", message); the
// language is described in docs/grammar.md.
#pragma once

#include "tendril/lsystem/syntax.h"

#include <string>
#include <string_view>

namespace tendril::lsystem {

// Names the turtle gives meaning to after '@' and '~' (docs/grammar.md, "Turtle").
inline constexpr std::string_view kAtModules[] = {"R", "M", "Tv", "Te", "O", "Climb"};
inline constexpr std::string_view kLeafSurface = "leaf";

syntax::Grammar parseGrammar(std::string_view text, const std::string& source);

}  // namespace tendril::lsystem
