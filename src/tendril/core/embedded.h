// Files from examples/ compiled into the library (species presets and other built-ins), so
// the tool works from any directory. The files in examples/ stay the single source.
#pragma once

#include <span>
#include <string_view>

namespace tendril {

struct EmbeddedFile {
  std::string_view path;      // relative to examples/, e.g. "species/japanese-ivy.json"
  std::string_view contents;
};

std::span<const EmbeddedFile> embeddedFiles();

inline const EmbeddedFile* findEmbeddedFile(std::string_view path) {
  for (const EmbeddedFile& f : embeddedFiles())
    if (f.path == path) return &f;
  return nullptr;
}

}  // namespace tendril
