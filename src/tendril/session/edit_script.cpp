#include "tendril/session/edit_script.h"

#include "tendril/core/error.h"
#include "tendril/session/session.h"

#include <fmt/format.h>

namespace tendril::session {

EditScript parseEditScript(const Json& json, const std::string& source) {
  if (!json.is_object())
    throw Error(source, "", "expected an edit script object {\"tendril_edits\": 1, \"edits\": [...]}, got " +
                                describeJson(json));
  JsonObject root(json, source);
  if (!root.has("tendril_edits"))
    throw root.error("tendril_edits", fmt::format("is required: the edit script format version (this build reads {})",
                                                  kEditScriptVersion));
  const int64_t version = root.integer("tendril_edits", 0, 0, 1000000);
  if (version != kEditScriptVersion)
    throw root.error("tendril_edits", fmt::format("edit script version {} is not supported (this build reads {})",
                                                  version, kEditScriptVersion));
  root.string("description", "");
  EditScript script;
  script.source = source;
  if (!root.has("edits")) throw root.error("edits", "is required: a list of timed edits");
  std::vector<JsonObject> edits = root.objectArray("edits");
  uint32_t last = 0;
  for (JsonObject& o : edits) {
    if (!o.has("at_step")) throw o.error("at_step", "is required: the step (from the script's start) to apply it at");
    const uint32_t at = uint32_t(o.integer("at_step", 0, 0, 100'000'000));
    if (at < last)
      throw o.error("at_step", fmt::format("steps must not decrease: {} comes after an edit at step {}", at, last));
    last = at;
    Edit edit = readEdit(o);
    o.finish();
    script.edits.push_back({at, std::move(edit)});
  }
  root.finish();
  return script;
}

EditScript loadEditScript(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw Error(path.string(), "", "edit script does not exist");
  return parseEditScript(readJsonFile(path), path.string());
}

Json editScriptToJson(const std::vector<TimedEdit>& edits) {
  Json list = Json::array();
  for (const TimedEdit& t : edits) {
    Json e = Json::object();
    e["at_step"] = t.atStep;
    const Json fields = editToJson(t.edit);
    for (auto it = fields.begin(); it != fields.end(); ++it) e[it.key()] = it.value();
    list.push_back(std::move(e));
  }
  return Json{{"tendril_edits", kEditScriptVersion}, {"edits", std::move(list)}};
}

void runEditScript(Editor& editor, const EditScript& script, uint32_t totalSteps,
                   const std::function<void(uint32_t)>& onStep) {
  // The script's clock is the editor's (steps run, never turned back by an undo); stepping
  // through the editor puts the steps in the journal (one entry per run).
  const uint32_t start = editor.stepsRun();
  uint32_t done = 0;
  auto stepTo = [&](uint32_t target) {
    while (editor.stepsRun() - start < target) {
      editor.step(1);
      if (onStep) onStep(++done);
    }
  };
  for (size_t i = 0; i < script.edits.size(); ++i) {
    const TimedEdit& t = script.edits[i];
    // Steps already made by "step" edits count too: an edit never waits for a step in the past.
    stepTo(t.atStep);
    try {
      editor.apply(t.edit);
    } catch (const Error& e) {
      const std::string where = fmt::format("/edits/{}", i);
      // "cut at step 2: /plant: there is no plant 4": the edit, then where in it.
      std::string inner = e.source() == editName(t.edit) ? std::string() : e.source();
      if (!e.location().empty()) inner += (inner.empty() ? "" : ":") + e.location();
      throw Error(script.source, where,
                  fmt::format("{} at step {}: {}{}", editName(t.edit), t.atStep, inner.empty() ? "" : inner + ": ",
                              e.message()));
    }
  }
  stepTo(totalSteps);
}

}  // namespace tendril::session
