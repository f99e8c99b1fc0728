// tendril validate SCENE: reads a scene, loads its meshes and checks its seed points without
// growing anything.
#include "commands.h"

#include "tendril/core/log.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

namespace tendril::cli {
namespace {

int runValidate(const std::string& path, const CommonOptions& common) {
  applyCommonOptions(common);
  scene::Scene scene = scene::loadScene(path);
  size_t obstacles = scene.obstacles.size(), plants = scene.plants.size();
  session::Session session(std::move(scene));  // builds the environment and seeds the plants
  if (!common.quiet)
    log::info("{}: ok ({} obstacles, {} plants, {} lights)", path, obstacles, plants,
              session.environment().lights().size());
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
