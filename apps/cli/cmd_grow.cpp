// tendril grow SCENE -o DIR: grows every plant of a scene and writes plant.glb / plant.obj (and
// plant-wind.glb, a looping wind animation, when asked).
#include "commands.h"
#include "plant_output.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/progress.h"
#include "tendril/core/timer.h"
#include "tendril/io/export_model.h"
#include "tendril/wind/gltf_animation.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"
#include "tendril/plant/plant_model.h"
#include "tendril/scene/scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"
#include "tendril/wind/sph.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <set>

namespace tendril::cli {
namespace {

struct GrowOptions {
  std::string scene;
  std::string outDir;
  int64_t steps = -1;
  int64_t seed = -1;
  int64_t every = 0;
  double windAnimation = -1.0;  // seconds; < 0: the scene's output.wind_animation
  bool windFrames = false;      // also every frame of the clip as its own .glb
  double growthAnimation = 0.0; // seconds; > 0: plant-growth.glb, the plants growing as they move
  std::string formats = "glb,obj";
  LodOptions lod;
  CommonOptions common;
};

int runGrow(const GrowOptions& o) {
  applyCommonOptions(o.common);
  std::set<std::string> formats = parseFormats(o.formats);
  scene::Scene scene = scene::loadScene(o.scene);
  if (o.steps >= 0) scene.steps = static_cast<int>(o.steps);
  if (o.seed >= 0) scene.seed = static_cast<uint64_t>(o.seed);
  applyLodOptions(o.lod, scene.output);
  if (o.windFrames && !((o.windAnimation >= 0.0 ? float(o.windAnimation) : scene.output.animationSeconds) > 0.0f))
    throw Error("command line", "--wind-frames",
                "needs a wind clip: --wind-animation SECONDS or the scene's output.wind_animation");
  std::filesystem::path outDir = prepareOutputDir(o.outDir);

  Timer total;
  session::Session session(std::move(scene));
  const scene::Scene& sc = session.scene();

  // Meshes the plants (and obstacles, if asked) once for both writers; `stem` names the files.
  std::vector<std::string> written;
  io::ExportScene exportScene;
  auto writeFiles = [&](const std::string& stem) {
    for (std::string& f : writePlantFiles(session, outDir, stem, formats, o.scene, exportScene))
      written.push_back(std::move(f));
  };

  double exportSeconds = 0.0;
  {
    Progress progress("growing", uint64_t(sc.steps), !o.common.quiet);
    session.run(uint32_t(sc.steps), [&](uint32_t done) {
      progress.update(done, fmt::format("{} segments", session.segmentCount()));
      // --every K: a numbered sequence, plant_000040.glb after step 40, ...
      if (o.every > 0 && done % uint32_t(o.every) == 0) {
        Timer t;
        writeFiles(fmt::format("plant_{:06d}", done));
        exportSeconds += t.seconds();
      }
    });
    progress.finish(fmt::format("{} segments", session.segmentCount()));
  }
  double growSeconds = total.seconds() - exportSeconds;
  const size_t sequenceFiles = written.size();
  written.clear();
  writeFiles("plant");

  // A looping clip of the grown plants moving in the scene's wind (Growth-Flow motion).
  float clipSeconds = o.windAnimation >= 0.0 ? float(o.windAnimation) : sc.output.animationSeconds;
  if (clipSeconds > 0.0f) {
    const std::vector<wind::AnimatedPlant> animated = session::animatedPlants(session, exportScene);
    const wind::WindAnimationOptions a = session::windClipOptions(session, clipSeconds);
    std::filesystem::path file = outDir / "plant-wind.glb";
    wind::writeWindAnimationGlb(animated, session.environment().windField(), a, file);
    written.push_back(file.string());
    // The per-step sequence: the same motion frame by frame, leaves moving on their own.
    if (o.windFrames)
      for (std::filesystem::path& f : wind::writeWindFrames(animated, session.environment().windField(), a, outDir, "plant-wind"))
        written.push_back(f.string());
  }
  // A clip of the plants growing (joints scaling in by the age of their nodes) as they move.
  if (o.growthAnimation > 0.0) {
    const std::vector<wind::AnimatedPlant> animated = session::animatedPlants(session, exportScene);
    wind::WindAnimationOptions a = session::windClipOptions(session, float(o.growthAnimation));
    a.maxJoints = std::max(sc.output.animationJoints, 256);
    a.growth = true;
    std::filesystem::path file = outDir / "plant-growth.glb";
    wind::writeWindAnimationGlb(animated, session.environment().windField(), a, file);
    written.push_back(file.string());
  }

  if (!o.common.quiet) {
    size_t segments = 0, leaves = 0;
    for (const plant::PlantModel& p : exportScene.plants) {
      plant::PlantStats s = plant::computeStats(p);
      segments += s.nodes;
      leaves += s.leaves;
      log::info("{}: {} segments, {} leaves, {:.2f} m of stem, {} tips", p.name, s.nodes, s.leaves, s.totalLength,
                s.tips);
    }
    if (const wind::SphAir* air = session.air(); air && session.airSteps() > 0)
      log::info("simulated air: {} particles at {} m spacing, {:.1f} ms per step on average ({} substeps in the last)",
                air->count(), air->settings().spacing, 1e3 * session.airSeconds() / session.airSteps(),
                air->timings().substeps);
    std::string files;
    for (const auto& w : written) files += (files.empty() ? "" : ", ") + w;
    if (sequenceFiles > 0) files += fmt::format(" and a sequence of {} file(s) in {}", sequenceFiles, outDir.string());
    log::info("grew {} plant(s) in {} steps: {} segments, {} leaves (growth {:.3f} s, total {:.3f} s); wrote {}",
              exportScene.plants.size(), session.stepCount(), segments, leaves, growSeconds, total.seconds(), files);
  }
  return 0;
}

RegisterCommand registerGrow("grow", "Grow every plant of a scene and write the result (.glb, .obj)", 10,
                             [](CLI::App& sub) -> std::function<int()> {
  auto o = std::make_shared<GrowOptions>();
  sub.add_option("scene", o->scene, "Scene file (JSON, see docs/scene-format.md)")->required();
  sub.add_option("-o,--output", o->outDir, "Output directory (created if missing): plant.glb, plant.obj")
      ->required();
  sub.add_option("--steps", o->steps, "Growth steps (overrides the scene's \"steps\")")->check(CLI::Range(0, 10000000));
  sub.add_option("--seed", o->seed, "Scene seed (overrides the scene's \"seed\")")->check(CLI::NonNegativeNumber);
  sub.add_option("--every", o->every,
                 "Also write the plants every K steps as a numbered sequence (plant_000040.glb, ...)")
      ->check(CLI::Range(1, 10000000));
  sub.add_option("--wind-animation", o->windAnimation,
                 "Also write plant-wind.glb: a looping clip of this many seconds of the plants moving in the "
                 "scene's wind (overrides output.wind_animation; 0 = none)")
      ->check(CLI::Range(0.0, 600.0));
  sub.add_flag("--wind-frames", o->windFrames,
               "Also write every frame of the wind clip as plant-wind_0000.glb, ... (static meshes of the "
               "clip's poses, for tools that play no skins or morph targets)");
  sub.add_option("--growth-animation", o->growthAnimation,
                 "Also write plant-growth.glb: a clip of this many seconds of the plants growing while they move "
                 "in the scene's wind (0 = none)")
      ->check(CLI::Range(0.0, 600.0));
  sub.add_option("--format", o->formats, "Comma-separated output formats: glb, obj, skeleton (plant.skeleton.json)")
      ->capture_default_str();
  addLodOptions(sub, o->lod);
  addCommonOptions(sub, o->common);
  return [o] { return runGrow(*o); };
});

}  // namespace
}  // namespace tendril::cli
