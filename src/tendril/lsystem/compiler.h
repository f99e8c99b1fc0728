// Grammar text → compiled Grammar. Every error in the text, syntax or meaning (unknown names,
// parameter counts, unbalanced brackets, ...), is an Error(source, "line:col", message).
#pragma once

#include "tendril/lsystem/grammar.h"

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tendril::lsystem {

struct CompileOptions {
  // Values replacing the grammar's `define:` constants (an unknown name is an Error).
  std::vector<std::pair<std::string, double>> defines;
  // Relative texture paths in `leaf shapes:` and `bark:` resolve here.
  std::filesystem::path dir;
};

std::shared_ptr<const Grammar> compileGrammar(std::string_view text, const std::string& source,
                                              const CompileOptions& options = {});

}  // namespace tendril::lsystem
