// Species documents of every model, found one way: a built-in preset (examples/species/*.json,
// compiled in) by name, found by the model its "model" key declares, or a species .json file by
// path. Each model then reads the document's keys with its own species reader.
#pragma once

#include "tendril/core/json_reader.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace tendril::models {

// The model a species document declares: its "model" key ("climb" when it has none, as for a
// scene plant).
std::string declaredModel(const Json& document);

// Names of the built-in presets that declare `model`, in the order they are compiled in.
std::vector<std::string> builtinSpeciesNames(std::string_view model);

struct SpeciesDocument {
  Json json;
  std::string source;          // how errors name it: the file, or "<built-in>/species/<name>.json"
  std::filesystem::path dir;   // resolves the document's relative paths ("" for presets)
};

// The species `ref` names — a built-in preset, or a .json path relative to `baseDir` — checked
// to declare `model`. An unknown preset or a missing file is an Error at (source, pointer); a
// document for another model is an Error at the document's "/model".
SpeciesDocument loadSpeciesDocument(std::string_view model, const std::string& ref,
                                    const std::filesystem::path& baseDir, const std::string& source,
                                    const std::string& pointer);

}  // namespace tendril::models
