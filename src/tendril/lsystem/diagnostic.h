// Grammar errors shown with their source line and a caret under the column, for the CLI (under
// the one-line error) and the studio (inline):
//
//    12 | A(x) : x > 0 -> B(x /)
//       |                      ^
#pragma once

#include "tendril/core/error.h"

#include <cstdint>
#include <string>
#include <string_view>

namespace tendril::lsystem {

// The excerpt for line:col of `text` (1-based; tabs kept so the caret lines up). Empty when
// the line does not exist.
std::string renderDiagnostic(std::string_view text, uint32_t line, uint32_t col);
// The excerpt for an Error located at "line:col"; empty for other locations.
std::string renderDiagnostic(std::string_view text, const Error& error);

}  // namespace tendril::lsystem
