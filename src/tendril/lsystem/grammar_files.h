// Grammar files: a path to a .ls file, or the name of a built-in grammar (examples/grammars/
// <name>.ls, e.g. "japanese-ivy").
#pragma once

#include "tendril/lsystem/compiler.h"
#include "tendril/lsystem/grammar.h"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tendril::lsystem {

// A name without '/' and without the .ls extension is a built-in grammar; anything else is a
// path, relative to baseDir. A missing file or unknown name is Error(source, pointer, ...);
// errors inside the grammar name the grammar file and line:col. Relative textures in the
// grammar resolve against its own directory.
std::shared_ptr<const Grammar> loadGrammar(const std::string& nameOrPath, const std::filesystem::path& baseDir,
                                           const CompileOptions& options = {}, const std::string& source = "grammar",
                                           const std::string& pointer = "");
std::shared_ptr<const Grammar> loadGrammarFile(const std::filesystem::path& path, const CompileOptions& options = {});

std::vector<std::string> builtinGrammarNames();

// The text behind a grammar's source name (a file path or a built-in's "<built-in>/..."), for
// diagnostics; nullopt when it cannot be read.
std::optional<std::string> grammarSourceText(const std::string& source);

}  // namespace tendril::lsystem
