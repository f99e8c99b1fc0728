#include "tendril/models/species_presets.h"

#include "tendril/core/embedded.h"
#include "tendril/core/error.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace tendril::models {

namespace {

constexpr std::string_view kSpeciesDir = "species/";
constexpr std::string_view kExtension = ".json";

bool isSpeciesPreset(std::string_view path) {
  return path.rfind(kSpeciesDir, 0) == 0 && path.size() > kSpeciesDir.size() + kExtension.size() &&
         path.substr(path.size() - kExtension.size()) == kExtension;
}

}  // namespace

std::string declaredModel(const Json& document) {
  if (!document.is_object()) return "climb";
  auto it = document.find("model");
  return it != document.end() && it->is_string() ? it->get<std::string>() : std::string("climb");
}

std::vector<std::string> builtinSpeciesNames(std::string_view model) {
  std::vector<std::string> names;
  for (const EmbeddedFile& f : embeddedFiles()) {
    if (!isSpeciesPreset(f.path)) continue;
    if (declaredModel(parseJson(f.contents, std::string(f.path))) != model) continue;
    names.emplace_back(f.path.substr(kSpeciesDir.size(), f.path.size() - kSpeciesDir.size() - kExtension.size()));
  }
  return names;
}

SpeciesDocument loadSpeciesDocument(std::string_view model, const std::string& ref,
                                    const std::filesystem::path& baseDir, const std::string& source,
                                    const std::string& pointer) {
  const bool isPath = ref.find('/') != std::string::npos ||
                      (ref.size() > kExtension.size() && ref.compare(ref.size() - kExtension.size(), kExtension.size(),
                                                                     kExtension.data()) == 0);
  SpeciesDocument d;
  if (!isPath) {
    const EmbeddedFile* f = findEmbeddedFile(std::string(kSpeciesDir) + ref + std::string(kExtension));
    if (f) {
      d.source = "<built-in>/" + std::string(f->path);
      d.json = parseJson(f->contents, d.source);
    }
    if (f && declaredModel(d.json) != model)
      throw Error(source, pointer,
                  fmt::format("species \"{}\" is for the \"{}\" model, not \"{}\"", ref, declaredModel(d.json), model));
    if (!f) {
      std::string names;
      for (const std::string& n : builtinSpeciesNames(model)) names += (names.empty() ? "" : ", ") + n;
      throw Error(source, pointer,
                  fmt::format("unknown species \"{}\" (built-in {} species: {}; or give a path to a .json file)", ref,
                              model, names));
    }
    return d;
  }
  std::filesystem::path p = std::filesystem::path(ref).is_absolute() ? std::filesystem::path(ref) : baseDir / ref;
  if (!std::filesystem::exists(p)) throw Error(source, pointer, fmt::format("species file {} does not exist", p.string()));
  d.source = p.string();
  d.dir = p.parent_path();
  d.json = readJsonFile(p);
  if (!d.json.is_object()) throw Error(d.source, "/", "expected an object, got " + describeJson(d.json));
  const Json* m = d.json.contains("model") ? &d.json["model"] : nullptr;
  if (m && !m->is_string()) throw Error(d.source, "/model", "expected a string, got " + describeJson(*m));
  if (declaredModel(d.json) != model)
    throw Error(d.source, "/model",
                fmt::format("this species is for the \"{}\" model, not \"{}\"", declaredModel(d.json), model));
  return d;
}

}  // namespace tendril::models
