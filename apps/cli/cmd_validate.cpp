// tendril validate SCENE: reads a scene, loads its meshes and checks its seed points, then grows
// each plant on its own for its first steps and reports the seeds that will not grow (that stop
// in those steps: the Session's growth diagnostics, models/diagnosis.h), without running the
// scene. Such seeds are warnings: the exit code is 0.
#include "commands.h"

#include "tendril/core/log.h"
#include "tendril/models/diagnosis.h"
#include "tendril/scene/scene.h"
#include "tendril/session/grow_alone.h"
#include "tendril/session/session.h"

#include <algorithm>

namespace tendril::cli {
namespace {

// Each plant is grown alone for this many steps (at most the scene's): long enough for a
// climber without support to die (6 unsupported segments) and for a stalled grammar to show.
constexpr uint32_t kTrialSteps = 100;

int runValidate(const std::string& path, const CommonOptions& common) {
  applyCommonOptions(common);
  scene::Scene scene = scene::loadScene(path);
  size_t obstacles = scene.obstacles.size(), plants = scene.plants.size();
  const uint32_t trial = std::min<uint32_t>(kTrialSteps, uint32_t(std::max(scene.steps, 0)));
  session::Session session(std::move(scene));  // builds the environment and seeds the plants
  size_t wontGrow = 0;
  for (size_t i = 0; i < session.plantCount(); ++i) {
    const models::PlantSpec& spec = session.plantSpec(i);
    std::unique_ptr<models::PlantSystem> alone = session::growAlone(session, spec, trial);
    // Only a plant that stops: one that grows slowly (in shade, say) is judged at the end of a run.
    const auto problem = models::diagnoseGrowth(*alone, 0, spec, session.environment());
    if (problem && problem->stopped) {
      log::warn("{}:{}: {}", path, spec.pointer, problem->message);
      ++wontGrow;
    }
  }
  if (!common.quiet)
    log::info("{}: ok ({} obstacles, {} plants, {} lights{})", path, obstacles, plants,
              session.environment().lights().size(),
              wontGrow ? fmt::format("; {} of the plants will not grow as their species does", wontGrow) : "");
  return 0;
}

RegisterCommand registerValidate("validate", "Check a scene file without running it", 20,
                                 [](CLI::App& sub) -> std::function<int()> {
  auto path = std::make_shared<std::string>();
  auto common = std::make_shared<CommonOptions>();
  sub.add_option("scene", *path, "Scene file (JSON)")->required();
  addCommonOptions(sub, *common);
  return [path, common] { return runValidate(*path, *common); };
});

}  // namespace
}  // namespace tendril::cli
