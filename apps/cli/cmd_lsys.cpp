// tendril lsys GRAMMAR -o OUT.glb: derives an L-system grammar (docs/grammar.md) and writes
// the plant its turtle draws. It grows a one-plant scene (scene/one_plant_scene.h) through a
// Session, so a scene holding the same plant grows the same one. Errors inside the grammar print
// the one-line error and, under it, the grammar line with a caret at the column.
#include "commands.h"
#include "plant_output.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/progress.h"
#include "tendril/core/timer.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"
#include "tendril/lsystem/lsystem.h"
#include "tendril/lsystem/lsystem_model.h"
#include "tendril/scene/one_plant_scene.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdio>
#include <filesystem>
#include <iostream>

namespace tendril::cli {
namespace {

struct LsysOptions {
  std::string grammar;
  std::string output;
  int64_t steps = -1;
  int64_t seed = -1;
  std::vector<std::string> defines;
  std::string scene;
  std::string at;
  std::string heading;
  bool print = false;
  int radialSegments = 0;  // 0: the scene's output.radial_segments (8 without a scene)
  std::string formats;     // empty: the output's extension
  LodOptions lod;
  CommonOptions common;
};

std::pair<std::string, double> parseDefine(const std::string& text) {
  size_t eq = text.find('=');
  std::string name = eq == std::string::npos ? "" : text.substr(0, eq);
  std::string value = eq == std::string::npos ? "" : text.substr(eq + 1);
  size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (name.empty() || used == 0 || used != value.size() || !std::isfinite(v))
    throw Error("command line", "--define", fmt::format("expected NAME=NUMBER, got \"{}\"", text));
  return {name, v};
}

// An Error the Session gave for the one plant, said as the command line and the grammar say it:
// a start inside an obstacle is --at's; a run-time error of the grammar's Start: or axiom is
// the grammar's own (file:line:col), so that its line is shown with a caret.
Error commandLineError(const Error& e, const std::string& sceneSource, const lsystem::Grammar& grammar,
                       const LsysOptions& o) {
  if (e.source() != sceneSource) return e;
  if (e.location() == "/plants/0/position")
    return Error("command line", "--at",
                 fmt::format("{} of {}; give --at x,y,z in front of a surface", e.message(), o.scene));
  const std::string prefix = grammar.source + ":";
  if (e.location() == "/plants/0/grammar" && e.message().starts_with(prefix)) {
    std::string rest = e.message().substr(prefix.size());
    if (rest.starts_with(" ")) return Error(grammar.source, "", rest.substr(1));
    const size_t colon = rest.find(": ");
    if (colon != std::string::npos) return Error(grammar.source, rest.substr(0, colon), rest.substr(colon + 2));
  }
  return e;
}

int runLsys(const LsysOptions& o) {
  applyCommonOptions(o.common);
  std::filesystem::path out(o.output);
  std::string ext = out.extension().string();
  if (ext != ".glb" && ext != ".obj")
    throw Error("command line", "-o", fmt::format("the output must end in .glb or .obj, got \"{}\"", o.output));
  // --format writes each format beside the output, named after its stem.
  const std::set<std::string> formats = o.formats.empty() ? std::set<std::string>{ext.substr(1)} : parseFormats(o.formats);
  const std::filesystem::path outDir = out.parent_path().empty() ? std::filesystem::path(".") : out.parent_path();

  lsystem::CompileOptions compile;
  for (const std::string& d : o.defines) compile.defines.push_back(parseDefine(d));
  Timer total;
  std::shared_ptr<const lsystem::Grammar> grammar =
      lsystem::loadGrammar(o.grammar, std::filesystem::current_path(), compile, "command line", "GRAMMAR");

  // The one-plant scene: the grammar standing at --at, its first heading --heading, seeded with
  // --seed (default: the grammar's seed:), in the scene given (its environment, seed and output
  // settings; not its plants) or in an empty one. A scene file holding this plant grows the
  // same plant.
  std::optional<scene::Scene> base;
  if (!o.scene.empty()) base = scene::loadScene(o.scene);
  models::PlantSpec plant;
  plant.name = grammar->name.empty() ? std::filesystem::path(o.grammar).stem().string() : grammar->name;
  if (!o.at.empty()) plant.position = parseVec3(o.at, "--at");
  if (!o.heading.empty()) {
    const Vec3 h = parseVec3(o.heading, "--heading");
    if (!(h.norm() > 1e-6f)) throw Error("command line", "--heading", "the heading must not be zero");
    plant.direction = h.normalized();
  }
  plant.seed = o.seed >= 0 ? uint64_t(o.seed) : grammar->seed;
  std::optional<int> length;
  if (o.steps >= 0) length = int(o.steps);
  const int steps = length.value_or(grammar->derivationLength);
  scene::Scene sc = scene::onePlantScene(lsystem::lsystemPlant(std::move(plant), grammar, length), steps, base);
  if (o.radialSegments > 0) sc.output.radialSegments = o.radialSegments;
  applyLodOptions(o.lod, sc.output);
  const std::string sceneSource = sc.source;
  std::unique_ptr<session::Session> session;
  try {
    session = std::make_unique<session::Session>(std::move(sc));
  } catch (const Error& e) {
    throw commandLineError(e, sceneSource, *grammar, o);
  }
  auto derivation = [&] { return lsystem::derivationOf(session->system(0), session->indexInSystem(0)); };
  {
    Progress progress("deriving", uint64_t(std::max(steps, 0)), !o.common.quiet);
    session->run(uint32_t(std::max(steps, 0)), [&](uint32_t done) {
      progress.update(done, fmt::format("{} modules", derivation()->string().size()));
    });
    progress.finish(fmt::format("{} modules", derivation()->string().size()));
  }
  double deriveSeconds = total.seconds();
  const lsystem::LSystem& ls = *derivation();
  if (o.print) std::cout << ls.text() << "\n";

  io::ExportScene exportScene;
  const std::vector<std::string> written =
      writePlantFiles(*session, outDir, out.stem().string(), formats, grammar->source, exportScene);

  if (!o.common.quiet) {
    const plant::PlantModel& p = exportScene.plants[0];
    plant::PlantStats s = plant::computeStats(p);
    log::info("{}: {} steps, {} modules; {} segments, {} leaves, {} polygon meshes (derivation {:.2f} s, total "
              "{:.2f} s); wrote {}",
              p.name, ls.stepCount(), ls.string().size(), s.nodes, s.leaves, p.meshes.size(), deriveSeconds,
              total.seconds(), fmt::join(written, ", "));
  }
  return 0;
}

RegisterCommand registerLsys("lsys", "Derive an L-system grammar and write the plant it draws (.glb, .obj)", 15,
                             [](CLI::App& sub) -> std::function<int()> {
  auto o = std::make_shared<LsysOptions>();
  sub.add_option("grammar", o->grammar, "Grammar: a .ls file or a built-in name (see docs/grammar.md)")->required();
  sub.add_option("-o,--output", o->output, "Output file: .glb or .obj")->required();
  sub.add_option("-n,--steps", o->steps, "Derivation steps (overrides the grammar's derivation length)")
      ->check(CLI::Range(0, 10000000));
  sub.add_option("--seed", o->seed, "The plant's seed, as a scene plant's \"seed\" (default: the grammar's seed:)")
      ->check(CLI::Range(int64_t(0), int64_t(1) << 53));
  sub.add_option("-D,--define", o->defines, "Override a define: constant, NAME=NUMBER (repeatable)");
  sub.add_option("--scene", o->scene,
                 "Grow in this scene in place of its plants (its obstacles, lights, strokes, wind, seed, output)");
  sub.add_option("--at", o->at, "Where the plant stands, x,y,z (m); default 0,0,0");
  sub.add_option("--heading", o->heading, "The turtle's first heading, x,y,z; default 0,1,0 (up)");
  sub.add_flag("--print", o->print, "Print the derived string");
  sub.add_option("--format", o->formats,
                 "Comma-separated formats to write beside OUT, named after its stem: glb, obj, skeleton "
                 "(default: OUT's extension)");
  sub.add_option("--radial-segments", o->radialSegments,
                 "Vertices around each branch (overrides the scene's output.radial_segments; default 8)")
      ->check(CLI::Range(3, 64));
  addLodOptions(sub, o->lod);
  addCommonOptions(sub, o->common);
  return [o]() -> int {
    try {
      return runLsys(*o);
    } catch (const Error& e) {
      // The one-line error, then the grammar line it points at.
      std::fprintf(stderr, "tendril: error: %s\n", e.what());
      if (auto text = lsystem::grammarSourceText(e.source())) {
        std::string excerpt = lsystem::renderDiagnostic(*text, e);
        std::fputs(excerpt.c_str(), stderr);
      }
      return 2;
    }
  };
});

}  // namespace
}  // namespace tendril::cli
