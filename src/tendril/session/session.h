// A Session owns one open scene: its Environment, every plant of every model, and the clock.
// Apps (CLI, studio) drive a Session; they never reach around it.
#pragma once

#include "tendril/core/archive.h"
#include "tendril/env/environment.h"
#include "tendril/models/diagnosis.h"
#include "tendril/models/registry.h"
#include "tendril/plant/plant_model.h"
#include "tendril/scene/scene.h"
#include "tendril/wind/sph.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace tendril::session {

class Session {
 public:
  // Builds the environment and seeds every plant. Throws Error for seeds inside obstacles and
  // other bad plant settings, naming the scene file and the plant's JSON pointer.
  explicit Session(scene::Scene scene);
  // The same, keeping the scene's JSON document so that a session file can rebuild the
  // environment (session_file.h). `baseDir` resolves the scene's relative paths.
  Session(scene::Scene scene, Json sceneDocument, std::filesystem::path baseDir);
  // Reads a scene file and opens it (keeps the document, as above).
  static std::unique_ptr<Session> open(const std::filesystem::path& scenePath);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const scene::Scene& scene() const { return scene_; }
  env::Environment& environment() { return *env_; }
  const env::Environment& environment() const { return *env_; }

  // One growth step of every plant.
  void step();
  // Up to `steps` steps, stopping early when nothing grows any more. `onStep(done)` is called
  // after each step (progress reports). Ends with reportGrowth().
  void run(uint32_t steps, const std::function<void(uint32_t)>& onStep = {});
  uint32_t stepCount() const { return steps_; }
  bool finished() const;

  // Snapshots of every plant, in scene order.
  std::vector<plant::PlantModel> plants() const;
  // The Growth-Flow constants of every plant, in scene order.
  std::vector<plant::GrowthFlowSpecies> growthFlow() const;
  size_t segmentCount() const;

  // Plants that have stopped growing in their first steps or stay far below their species'
  // size, and why (models/diagnosis.h), in plant order; none for healthy plants.
  struct GrowthReport {
    size_t plant = 0;
    models::GrowthProblem problem;
  };
  std::vector<GrowthReport> diagnoseGrowth() const;
  // diagnoseGrowth(), writing a warning for each problem not reported before (a plant is
  // reported again only for another cause; a cap is left to the model's own warning). What
  // run(), `tendril edit`, the Python module's grow and the studio call when growth stops.
  std::vector<GrowthReport> reportGrowth();

  // --- plants at run time ---
  // Adds a plant now (any model). `description` is the plant as a scene-file plant object;
  // plants added without one cannot be written to a session file. Throws Error for a seed
  // inside an obstacle and other bad settings. Returns the plant's index.
  uint32_t addPlant(models::PlantSpec spec, Json description = {});
  // Adds a plant from a scene-file plant object (docs/scene-format.md); errors name `source`
  // and the object's keys.
  uint32_t addPlant(const Json& plant, const std::string& source);
  size_t plantCount() const { return plants_.size(); }
  const models::PlantSpec& plantSpec(size_t plant) const { return specs_.at(plant).spec; }
  // The plant's scene-file object (null for plants added from code).
  const Json& plantDescription(size_t plant) const { return specs_.at(plant).description; }
  // Replaces a plant's settings live from a new scene-file plant object of the same model
  // (e.g. changed species keys). Throws Error when the model cannot change them live.
  void setPlantDescription(size_t plant, const Json& description, const std::string& source);
  // The plant's own system and its index there.
  // (A plant's system taken for changing marks its stems for the supports' next update.)
  models::PlantSystem& system(size_t plant) {
    const size_t s = plants_.at(plant).system;
    if (staleSystems_.size() <= s) staleSystems_.resize(systems_.size(), 0);
    staleSystems_[s] = 1;
    return *systems_[s];
  }
  const models::PlantSystem& system(size_t plant) const { return *systems_[plants_.at(plant).system]; }
  size_t indexInSystem(size_t plant) const { return plants_.at(plant).index; }
  // Plants as supports: the nodes of other plants that cling to the stems of the host's nodes
  // marked in `removed` (a cut branch of the host, as the host is before the cut): per plant,
  // the first such node on each path from its root, whose subtree goes with it. A node clings
  // to the support surface nearest it within its species' support reach (0.1 m for species
  // that state none). Plants of models that cannot be cut are left out.
  std::vector<std::pair<uint32_t, uint32_t>> clingingTo(size_t host, const std::vector<bool>& removed) const;
  // One system per model in use, in the order the models were first used.
  std::vector<models::PlantSystem*> systems();
  // Gives the environment the stems of the support plants that changed since it last had them
  // (edits do this as they are applied, a step as it starts), so that queries between steps
  // (what a climber clings to, a click on a trunk) see the plants as they are.
  void refreshSupports() { updateSupports(false); }
  // The bodies the simulated air may push, over every system that takes part in it
  // (models::AirCoupling; for particle plants, their grown branch particles).
  size_t airBodyCount() const;
  // The simulated air (wind mode sph), or null.
  wind::SphAir* air() { return air_.get(); }
  const wind::SphAir* air() const { return air_.get(); }
  // Wall-clock seconds the air's steps took in this process, and how many (for reports).
  double airSeconds() const { return airSeconds_; }
  uint32_t airSteps() const { return airSteps_; }

  // The scene document and directory (null/empty when built from a Scene alone).
  const Json& sceneDocument() const { return sceneDocument_; }
  const std::filesystem::path& baseDir() const { return baseDir_; }

  // --- climbers on plants (session/plant_attachments.cpp) ---
  // Where a plant clings to the stems of support plants: per node of `snapshot` (the plant as
  // plants() gives it), the host plant (index here) and host node whose stem surface is the
  // nearest surface within `reach` of the node's position, else {-1, -1}. The queries see the
  // stems of every model's system but the plant's own (as its growth does). A support plant
  // clings to nothing, so no two plants hold each other.
  struct Attachment {
    int32_t plant = -1;
    int32_t node = -1;
  };
  std::vector<Attachment> attachments(size_t plant, const plant::PlantModel& snapshot, float reach) const;

  // --- state ---
  // Everything that decides future steps: the environment's editable state (obstacle
  // transforms, lights, strokes, wind), every plant (its description and its system's state),
  // the simulated air and the step count. loadState restores it exactly: stepping on gives
  // bit-identical results to never having saved. Throws Error(source, "byte N", ...) for
  // damaged or mismatched input, leaving the session unchanged.
  std::vector<uint8_t> saveState() const;
  void loadState(std::span<const uint8_t> bytes, const std::string& source = "session state");
  // Hash of every plant snapshot and the environment's editable state (undo checks, tests).
  uint64_t stateHash() const;
  // Replaces the wind emitters (and, in sph mode, the simulated air's). Throws Error for an
  // emitter the air cannot use, leaving everything as it was.
  void setEmitters(std::vector<env::WindEmitter> emitters);
  // Commits environment edits (obstacle moves, strokes) and refreshes what depends on them.
  void environmentChanged();

  // --- obstacles at run time ---
  // The environment's obstacles are the scene's, then those imported since, in that order.
  // Imports a mesh file (any format env/mesh_import.h reads: .obj, .ply, .stl, .gltf, .glb,
  // .fbx...) as a new obstacle; a relative `path` is resolved against baseDir(). `scale` is
  // applied to the mesh in its own frame (as a scene's mesh "scale"); an empty name is the
  // file's stem. Throws Error naming the file for a missing, unreadable or empty mesh, and for
  // a non-positive scale, leaving the session as it was. Returns the obstacle's index.
  uint32_t importObstacle(const std::string& path, std::string name, const RigidTransform& worldFromLocal,
                          const Vec3& scale = Vec3::Ones(), const Vec3& color = Vec3(0.6f, 0.6f, 0.6f));
  // The mesh file of an imported obstacle as given to importObstacle ("" for the scene's own).
  const std::string& obstaclePath(uint32_t obstacle) const;
  // The factors the obstacle's mesh is scaled by in its own frame: (1, 1, 1) for the mesh as
  // the scene (or the import) made it.
  const Vec3& obstacleScale(uint32_t obstacle) const { return obstacleScales_.at(obstacle); }
  // Rescales an obstacle's mesh in its own frame (each factor in [1e-4, 1e4]; non-uniform is
  // allowed). Environment transforms are rigid, so the environment is rebuilt with the scaled
  // mesh (its distance field is built again on first use). Throws Error for a bad scale.
  void setObstacleScale(uint32_t obstacle, const Vec3& scale);
  // Changes whenever obstacle meshes change (an import, a rescale, an undo of either): views
  // that keep obstacle meshes fetch them again. The Environment object itself may be replaced
  // then, so do not keep references to environment() across edits.
  uint64_t obstacleRevision() const { return obstacleRevision_; }

 private:
  struct PlantRef {
    size_t system;  // index into systems_
    size_t index;   // plant index within that system
  };

  struct SpecEntry {
    models::PlantSpec spec;
    Json description;
    std::string text;  // description.dump(), compared on loadState
  };
  // An obstacle imported at run time (importObstacle); its mesh as read, unscaled.
  struct ImportedObstacle {
    std::string path;  // as given
    std::string name;
    Vec3 color = Vec3(0.6f, 0.6f, 0.6f);
    std::shared_ptr<const TriangleMesh> mesh;
    bool operator==(const ImportedObstacle& o) const {
      return path == o.path && name == o.name && color == o.color && mesh == o.mesh;
    }
  };
  size_t systemFor(const std::string& model);
  // loadState's phases: read and check (the session unchanged), then apply.
  struct Loaded;
  void readSavedPlants(ArchiveReader& in, const std::string& source, Loaded& loaded) const;
  void readSavedEnvironment(ArchiveReader& in, uint32_t version, Loaded& loaded) const;
  void restoreSystems(ArchiveReader& in, Loaded& loaded) const;
  void applyLoaded(Loaded&& loaded);
  // The mesh file behind an imported obstacle, read once per session (undo and redo reuse it).
  std::shared_ptr<const TriangleMesh> importedMesh(const std::string& path);
  // The environment's definition of obstacle `index` at its current scale (not transform).
  env::ObstacleDef obstacleDef(size_t index) const;
  // Replaces the environment with one made afresh from the scene's and the imported obstacles
  // at their scales, keeping every obstacle transform, light, stroke and the wind.
  void rebuildEnvironment(const std::vector<RigidTransform>& transforms);
  // Plants as supports (spec.support): gives the environment the stems and leaves of every
  // support plant, by system (session/plant_supports.cpp). A system's support plants are
  // snapshot again after anything may have changed them, and at every step while it grows
  // (`stepping`).
  void updateSupports(bool stepping);
  // Runs f(viewer) with the environment's queries seeing the stems of every system but `viewer`.
  template <class F>
  auto viewingAs(size_t viewer, F&& f) const {
    struct Restore {
      env::Environment& env;
      uint32_t before;
      ~Restore() { env.setStemViewer(before); }
    } restore{*env_, env_->stemViewer()};
    env_->setStemViewer(uint32_t(viewer));
    return f();
  }

  scene::Scene scene_;
  Json sceneDocument_;
  std::filesystem::path baseDir_;
  std::vector<SpecEntry> specs_;  // per plant; plants are only ever appended
  std::unique_ptr<env::Environment> env_;
  std::vector<std::unique_ptr<models::PlantSystem>> systems_;  // one per model in use
  std::vector<std::string> systemModels_;
  std::vector<PlantRef> plants_;  // per scene plant
  std::unique_ptr<wind::SphAir> air_;  // simulated air (wind mode sph)
  std::vector<ImportedObstacle> imported_;
  std::vector<Vec3> obstacleScales_;  // per obstacle, in environment order
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshCache_;  // resolved path -> mesh
  uint64_t obstacleRevision_ = 0;
  std::set<std::pair<size_t, models::GrowthCause>> reportedGrowth_;  // (plant, cause) warned of
  uint32_t steps_ = 0;
  bool supportsStale_ = true;        // every system's supports
  std::vector<uint8_t> staleSystems_;  // by system: taken for changing since its supports were given
  std::vector<bool> systemHasSupports_;  // by system, as last given to the environment
  double airSeconds_ = 0.0;
  uint32_t airSteps_ = 0;
};

}  // namespace tendril::session
