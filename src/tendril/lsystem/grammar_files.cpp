#include "tendril/lsystem/grammar_files.h"

#include "tendril/core/embedded.h"
#include "tendril/core/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <set>
#include <sstream>

namespace tendril::lsystem {

namespace {

constexpr std::string_view kGrammarDir = "grammars/";
constexpr std::string_view kBuiltinPrefix = "<built-in>/";
constexpr std::string_view kExtension = ".ls";

bool endsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::optional<std::string> readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) return std::nullopt;
  return s.str();
}

// Built-in grammars are the files of examples/grammars: compiled into the library when the
// build embeds them, otherwise read from the source tree this library was built from.
std::filesystem::path examplesGrammarDir() { return std::filesystem::path(TENDRIL_EXAMPLES_DIR) / "grammars"; }

std::optional<std::string> builtinText(const std::string& name) {
  if (const EmbeddedFile* f = findEmbeddedFile(std::string(kGrammarDir) + name + std::string(kExtension)))
    return std::string(f->contents);
  return readFile(examplesGrammarDir() / (name + std::string(kExtension)));
}

}  // namespace

std::vector<std::string> builtinGrammarNames() {
  std::set<std::string> names;
  for (const EmbeddedFile& f : embeddedFiles()) {
    std::string_view p = f.path;
    if (p.rfind(kGrammarDir, 0) == 0 && endsWith(p, kExtension))
      names.emplace(p.substr(kGrammarDir.size(), p.size() - kGrammarDir.size() - kExtension.size()));
  }
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(examplesGrammarDir(), ec))
    if (e.path().extension() == kExtension) names.insert(e.path().stem().string());
  return {names.begin(), names.end()};
}

std::shared_ptr<const Grammar> loadGrammarFile(const std::filesystem::path& path, const CompileOptions& options) {
  std::optional<std::string> text = readFile(path);
  if (!text) {
    std::error_code ec;
    throw Error(path.string(), "",
                std::filesystem::exists(path, ec) ? "cannot read the grammar file" : "grammar file does not exist");
  }
  CompileOptions o = options;
  if (o.dir.empty()) o.dir = path.parent_path();
  return compileGrammar(*text, path.string(), o);
}

std::shared_ptr<const Grammar> loadGrammar(const std::string& ref, const std::filesystem::path& baseDir,
                                           const CompileOptions& options, const std::string& source,
                                           const std::string& pointer) {
  bool isPath = ref.find('/') != std::string::npos || endsWith(ref, kExtension);
  if (isPath) {
    std::filesystem::path p = std::filesystem::path(ref).is_absolute() ? std::filesystem::path(ref) : baseDir / ref;
    p = p.lexically_normal();
    std::error_code ec;
    if (!std::filesystem::exists(p, ec))
      throw Error(source, pointer, fmt::format("grammar file {} does not exist", p.string()));
    return loadGrammarFile(p, options);
  }
  std::optional<std::string> text;
  bool valid = !ref.empty() && std::all_of(ref.begin(), ref.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
  });
  if (valid) text = builtinText(ref);
  if (!text) {
    std::string list;
    for (const std::string& n : builtinGrammarNames()) list += (list.empty() ? "" : ", ") + n;
    throw Error(source, pointer,
                fmt::format("unknown grammar \"{}\" (built-in: {}; or give a path to a .ls file)", ref,
                            list.empty() ? "none" : list));
  }
  CompileOptions o = options;
  if (o.dir.empty()) o.dir = examplesGrammarDir();
  return compileGrammar(*text, std::string(kBuiltinPrefix) + std::string(kGrammarDir) + ref + std::string(kExtension),
                        o);
}

std::optional<std::string> grammarSourceText(const std::string& source) {
  if (source.rfind(kBuiltinPrefix, 0) == 0) {
    std::string rel = source.substr(kBuiltinPrefix.size());
    if (const EmbeddedFile* f = findEmbeddedFile(rel)) return std::string(f->contents);
    return readFile(std::filesystem::path(TENDRIL_EXAMPLES_DIR) / rel);
  }
  return readFile(source);
}

}  // namespace tendril::lsystem
