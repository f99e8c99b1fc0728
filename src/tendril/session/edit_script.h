// Edit scripts (docs/edit-scripts.md): a JSON list of timed edits that replays an interactive
// session, e.g.
//   {"tendril_edits": 1, "edits": [{"at_step": 0, "edit": "seed_plant", "model": "particles",
//     "position": [0, 0, 0.05], "normal": [0, 0, 1]}, {"at_step": 40, "edit": "cut", ...}]}
// Reading is strict like the scene reader: unknown keys, wrong types and steps out of order
// are Errors naming the file and the JSON pointer.
#pragma once

#include "tendril/session/edit.h"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace tendril::session {

inline constexpr int kEditScriptVersion = 1;

struct EditScript {
  std::string source;
  std::vector<TimedEdit> edits;  // at_step non-decreasing; at_step counts from the script's start
};

EditScript parseEditScript(const Json& json, const std::string& source);
EditScript loadEditScript(const std::filesystem::path& path);
Json editScriptToJson(const std::vector<TimedEdit>& edits);

// Replays the script on the editor's session: steps until each edit's at_step (counted on the
// editor's clock, Editor::stepsRun(), from its value when called), applies it, then steps
// until `totalSteps` steps have run since the start (if more than the last edit needs). An
// edit that does not fit the session is an Error naming the script and the edit's pointer.
// `onStep(done)` reports steps.
void runEditScript(Editor& editor, const EditScript& script, uint32_t totalSteps = 0,
                   const std::function<void(uint32_t)>& onStep = {});

}  // namespace tendril::session
