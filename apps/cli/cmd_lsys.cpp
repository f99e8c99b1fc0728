// tendril lsys GRAMMAR -o OUT.glb: derives an L-system grammar (docs/grammar.md) and writes
// the plant its turtle draws. Errors inside the grammar print the one-line error and, under it,
// the grammar line with a caret at the column.
#include "commands.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/progress.h"
#include "tendril/core/timer.h"
#include "tendril/env/environment.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"
#include "tendril/lsystem/lsystem.h"
#include "tendril/scene/scene.h"

#include <fmt/format.h>

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
  int radialSegments = 8;
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

int runLsys(const LsysOptions& o) {
  applyCommonOptions(o.common);
  std::filesystem::path out(o.output);
  std::string ext = out.extension().string();
  if (ext != ".glb" && ext != ".obj")
    throw Error("command line", "-o", fmt::format("the output must end in .glb or .obj, got \"{}\"", o.output));

  lsystem::CompileOptions compile;
  for (const std::string& d : o.defines) compile.defines.push_back(parseDefine(d));
  Timer total;
  std::shared_ptr<const lsystem::Grammar> grammar =
      lsystem::loadGrammar(o.grammar, std::filesystem::current_path(), compile, "command line", "GRAMMAR");

  // The environment the ?E queries see: a scene's obstacles, lights and strokes, or nothing.
  env::Environment environment;
  std::optional<scene::Scene> scene;
  if (!o.scene.empty()) {
    scene = scene::loadScene(o.scene);
    scene::populateEnvironment(*scene, environment);
  } else {
    environment.commit();
  }

  lsystem::RunOptions run;
  if (!o.at.empty()) run.start.position = parseVec3(o.at, "--at");
  if (!o.heading.empty()) {
    const Vec3 h = parseVec3(o.heading, "--heading");
    if (!(h.norm() > 1e-6f)) throw Error("command line", "--heading", "the heading must not be zero");
    run.start.heading = h.normalized();
    // Keep U (the side away from a support) perpendicular to the new heading.
    Vec3 up = run.start.up - run.start.up.dot(run.start.heading) * run.start.heading;
    if (up.norm() < 1e-3f) up = anyPerpendicular(run.start.heading);
    run.start.up = up.normalized();
  }
  // The first few millimetres of growth must be outside every obstacle: a start on the ground
  // is fine, one at the foot of a wall standing on it is not. (The exact query ties there, at a
  // point on one surface and inside another; the distance grids do not.)
  const Vec3 probe = run.start.position + 0.005f * run.start.heading;
  if (scene && (environment.exactSignedDistance(probe, 1.0f) < 0.0f || environment.signedDistance(probe) < -1e-3f))
    throw Error("command line", "--at",
                fmt::format("the plant would start at ({:.3g}, {:.3g}, {:.3g}), inside an obstacle of {}; "
                            "give --at x,y,z in front of a surface",
                            run.start.position.x(), run.start.position.y(), run.start.position.z(), o.scene));
  if (o.seed >= 0) run.seed = uint64_t(o.seed);
  if (o.steps >= 0) run.derivationLength = int(o.steps);
  lsystem::LSystem ls(grammar, run);
  {
    Progress progress("deriving", uint64_t(std::max(ls.derivationLength(), 0)), !o.common.quiet);
    while (!ls.finished()) {
      ls.step(&environment);
      progress.update(ls.stepCount(), fmt::format("{} modules", ls.string().size()));
    }
    progress.finish(fmt::format("{} modules", ls.string().size()));
  }
  double deriveSeconds = total.seconds();
  if (o.print) std::cout << ls.text() << "\n";

  plant::PlantModel plant = ls.interpret();
  plant.name = grammar->name.empty() ? std::filesystem::path(o.grammar).stem().string() : grammar->name;
  plant::validate(plant, grammar->source);

  io::ExportScene exportScene;
  exportScene.plants.push_back(plant);
  if (scene && scene->output.includeObstacles) {
    for (uint32_t id = 0; id < environment.obstacleCount(); ++id) {
      const env::ObstacleInfo& info = environment.obstacle(id);
      io::NamedMesh m{info.name, environment.obstacleMesh(id), info.color};
      for (Vec3& v : m.mesh.positions) v = info.worldFromLocal.applyPoint(v);
      exportScene.meshes.push_back(std::move(m));
    }
  }
  io::ExportOptions options;
  options.mesh.radialSegments = o.radialSegments;
  if (ext == ".glb") io::writeGlb(exportScene, out, options);
  else io::writeObj(exportScene, out, options);

  if (!o.common.quiet) {
    plant::PlantStats s = plant::computeStats(plant);
    log::info("{}: {} steps, {} modules; {} segments, {} leaves, {} polygon meshes (derivation {:.2f} s, total "
              "{:.2f} s); wrote {}",
              plant.name, ls.stepCount(), ls.string().size(), s.nodes, s.leaves, plant.meshes.size(), deriveSeconds,
              total.seconds(), out.string());
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
  sub.add_option("--seed", o->seed, "Random seed (overrides the grammar's seed:)")->check(CLI::NonNegativeNumber);
  sub.add_option("-D,--define", o->defines, "Override a define: constant, NAME=NUMBER (repeatable)");
  sub.add_option("--scene", o->scene, "Grow in this scene's environment (its obstacles, lights, strokes)");
  sub.add_option("--at", o->at, "Where the plant stands, x,y,z (m); default 0,0,0");
  sub.add_option("--heading", o->heading, "The turtle's first heading, x,y,z; default 0,1,0 (up)");
  sub.add_flag("--print", o->print, "Print the derived string");
  sub.add_option("--radial-segments", o->radialSegments, "Vertices around each branch")->check(CLI::Range(3, 64));
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
