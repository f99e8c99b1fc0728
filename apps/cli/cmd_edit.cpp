// tendril edit SCENE|SESSION --script EDITS.json -o DIR: replays an edit script (seeding,
// cutting, dragging, painting... docs/edit-scripts.md) on a scene or a saved session, writes
// the plants as `grow` does and, if asked, the session file and a preview picture.
#include "commands.h"
#include "plant_output.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/progress.h"
#include "tendril/core/timer.h"
#include "tendril/io/atomic_file.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/session_file.h"

#include <fmt/format.h>

#include <algorithm>

namespace tendril::cli {
namespace {

struct EditOptions {
  std::string input;
  std::string script;
  std::string outDir;
  int64_t steps = -1;
  std::string save;
  std::string preview;
  std::string formats = "glb,obj";
  LodOptions lod;
  CommonOptions common;
};

int runEdit(const EditOptions& o) {
  applyCommonOptions(o.common);
  std::set<std::string> formats = parseFormats(o.formats);
  if (!std::filesystem::exists(o.input)) throw Error(o.input, "", "scene or session file does not exist");
  const session::EditScript script = session::loadEditScript(o.script);
  // Bad outputs are reported before any work. The output directory is made first, so that
  // --save and --preview may write into it (-o out --save out/session.tses).
  const std::filesystem::path outDir = prepareOutputDir(o.outDir);
  if (!o.save.empty()) io::checkOutputPath(o.save);
  if (!o.preview.empty()) io::checkOutputPath(o.preview);

  Timer total;
  std::unique_ptr<session::Session> session;
  std::vector<session::TimedEdit> journal;
  const bool fromSession = session::isSessionFile(o.input);
  if (fromSession) {
    session::LoadedSession loaded = session::loadSession(o.input);
    session = std::move(loaded.session);
    journal = std::move(loaded.journal);
  } else {
    session = session::Session::open(o.input);
  }
  scene::OutputSettings output = session->scene().output;  // with --lods, --lod-ratio
  applyLodOptions(o.lod, output);

  // Steps from the script's start: --steps, else the scene's "steps" (a scene) or just what the
  // script needs (a session that already grew).
  const uint32_t lastEdit = script.edits.empty() ? 0 : script.edits.back().atStep;
  uint32_t steps = o.steps >= 0 ? uint32_t(o.steps) : fromSession ? lastEdit : uint32_t(session->scene().steps);
  if (steps < lastEdit)
    throw Error("command line", "--steps",
                fmt::format("{} steps end before the script's last edit at step {}", steps, lastEdit));

  session::Editor editor(*session);
  editor.setJournal(std::move(journal));
  {
    Progress progress("editing", steps, !o.common.quiet);
    session::runEditScript(editor, script, steps, [&](uint32_t done) {
      progress.update(done, fmt::format("{} segments", session->segmentCount()));
    });
    progress.finish(fmt::format("{} segments", session->segmentCount()));
  }
  session->reportGrowth();  // plants that stopped early, and why

  io::ExportScene exported;
  std::vector<std::string> written = writePlantFiles(*session, outDir, "plant", formats, o.input, exported, &output);
  if (!o.save.empty()) {
    session::saveSession(o.save, *session, editor.journal());
    written.push_back(o.save);
  }
  if (!o.preview.empty()) {
    writePreview(*session, o.preview);
    written.push_back(o.preview);
  }
  if (!o.common.quiet) {
    std::string files;
    for (const auto& w : written) files += (files.empty() ? "" : ", ") + w;
    log::info("applied {} edit(s) over {} steps to {} plant(s), {} segments (total {:.2f} s); wrote {}",
              script.edits.size(), steps, session->plantCount(), session->segmentCount(), total.seconds(), files);
  }
  return 0;
}

RegisterCommand registerEdit("edit",
                             "Replay an edit script (seed, cut, drag, paint...) on a scene or session and write "
                             "the result",
                             15, [](CLI::App& sub) -> std::function<int()> {
  auto o = std::make_shared<EditOptions>();
  sub.add_option("input", o->input, "Scene file (JSON) or session file (.tses) to start from")->required();
  sub.add_option("--script", o->script, "Edit script (JSON, see docs/edit-scripts.md)")->required();
  sub.add_option("-o,--output", o->outDir, "Output directory (created if missing): plant.glb, plant.obj")
      ->required();
  sub.add_option("--steps", o->steps,
                 "Steps to run from the script's start (default: the scene's \"steps\"; for a session, up to the "
                 "last edit)")
      ->check(CLI::Range(0, 10000000));
  sub.add_option("--save", o->save, "Also write the session (.tses) to continue later");
  sub.add_option("--preview", o->preview, "Also render the result to this PNG (headless OpenGL)");
  sub.add_option("--format", o->formats, "Comma-separated output formats: glb, obj, skeleton (plant.skeleton.json)")
      ->capture_default_str();
  addLodOptions(sub, o->lod);
  addCommonOptions(sub, o->common);
  return [o] { return runEdit(*o); };
});

}  // namespace
}  // namespace tendril::cli
