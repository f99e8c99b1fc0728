#include "tendril/lsystem/diagnostic.h"

#include <fmt/format.h>

#include <charconv>

namespace tendril::lsystem {

std::string renderDiagnostic(std::string_view text, uint32_t line, uint32_t col) {
  if (line == 0) return "";
  size_t start = 0;
  for (uint32_t l = 1; l < line; ++l) {
    size_t nl = text.find('\n', start);
    if (nl == std::string_view::npos) return "";
    start = nl + 1;
  }
  size_t end = text.find('\n', start);
  std::string_view src = text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
  if (!src.empty() && src.back() == '\r') src.remove_suffix(1);
  std::string number = std::to_string(line);
  std::string pad(number.size(), ' ');
  // The caret line copies the tabs before the column so it lines up in any tab width.
  std::string marker;
  for (uint32_t c = 1; c < col; ++c) marker += (c - 1 < src.size() && src[c - 1] == '\t') ? '\t' : ' ';
  return fmt::format(" {} | {}\n {} | {}^\n", number, src, pad, marker);
}

std::string renderDiagnostic(std::string_view text, const Error& error) {
  const std::string& loc = error.location();
  size_t colon = loc.find(':');
  if (colon == std::string::npos) return "";
  uint32_t line = 0, col = 0;
  auto a = std::from_chars(loc.data(), loc.data() + colon, line);
  auto b = std::from_chars(loc.data() + colon + 1, loc.data() + loc.size(), col);
  if (a.ec != std::errc() || a.ptr != loc.data() + colon || b.ec != std::errc() || b.ptr != loc.data() + loc.size())
    return "";
  return renderDiagnostic(text, line, col);
}

}  // namespace tendril::lsystem
