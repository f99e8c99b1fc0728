// Interactive edits of a Session as plain values (seed 000 §5: seeding, branch seeding,
// cutting, dragging, painting attractors, moving obstacles and lights while plants grow), an
// Editor that applies them with undo/redo, and the picking helpers a viewport needs.
//
// Every edit is also a JSON object {"edit": "<kind>", ...} (docs/edit-scripts.md), so that a
// list of them replays an interactive session from the CLI (`tendril edit`) and in tests.
//
// Undo is exact: before an edit the Editor saves the whole Session state (Session::saveState)
// and undo restores those bytes, so the plants and the environment hash as before.
#pragma once

#include "tendril/core/json_reader.h"
#include "tendril/core/math.h"
#include "tendril/env/environment.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace tendril::session {

class Session;

inline constexpr uint32_t kNoParticle = std::numeric_limits<uint32_t>::max();

// --- the edits ---

// A new plant of any model standing at a surface point, growing along the surface normal.
struct SeedPlant {
  std::string model = "particles";  // a name in scene::modelTypes()
  // climb, particles: species preset name or .json path; lsystem: grammar name or .ls path;
  // graph: graph .json path. Empty = the model's default (climb, particles). Relative paths
  // are resolved against the scene's directory.
  std::string species;
  std::string name;                 // empty = "plant<N>"
  Vec3 position = Vec3::Zero();     // seed point (m)
  Vec3 normal = Vec3::UnitY();      // initial growth direction (the surface normal)
  uint64_t seed = 1;
};

// A new lateral apex on a grown branch particle of a particle plant (§5.1); it grows with the
// following steps.
struct SeedBranch {
  uint32_t plant = 0;
  uint32_t particle = 0;         // particle id (NodePick::particle)
  Vec3 direction = Vec3::UnitY();
};

// Cuts a plant at one of its segments: the segment and everything beyond it go. Particle
// plants: the piece falls and disappears (ParticleWorld::cut). Climbing plants: the subtree
// is removed at once (its tips die with it). Other models cannot be cut (Error). The segment
// is a node of the plant's snapshot or, on plants whose parts have handles (particle plants),
// the node holding a handle: handles keep their number while the plant grows on, node indices
// follow the snapshot's order, so scripts written for a later step say `particle`.
// Or, with `inside`, every branch of the plant where it enters the box (pruning a region: the
// first segment on each path from the root with its start, middle or tip inside, whatever the
// plant grew by then). With `remove` the pieces cut off are removed at once, as the paper's
// pruning does, instead of falling.
struct Cut {
  static constexpr uint32_t kByNode = std::numeric_limits<uint32_t>::max();
  uint32_t plant = 0;
  uint32_t node = 0;             // node index in the plant's snapshot (NodePick::node)
  uint32_t particle = kByNode;   // or: the node holding this handle (NodePick::particle)
  std::optional<Bounds3> inside;  // or: every branch where it enters this box
  bool remove = false;            // the cut-off pieces are removed at once rather than falling (pruning)
};

// A drag gesture on a particle plant through a soft constraint (§5.1): begin, any number of
// moves (and steps), end. The whole gesture is one undo entry. Connections strained past the
// species' threshold break in the world's own step.
struct DragBegin {
  uint32_t plant = 0;
  uint32_t particle = 0;
  Vec3 target = Vec3::Zero();
  float strength = 0.5f;  // 0–1
};
struct DragMove {
  Vec3 target = Vec3::Zero();
};
struct DragEnd {};

// Paints an attractor (or repulsor) stroke on surfaces. A new attracting stroke within its
// radius of a full-grown branch particle of a particle plant seeds a branch there, toward the
// stroke (§5.1).
struct PaintStroke {
  env::Stroke stroke;
};

// Moves/rotates an obstacle (by index in the environment) while plants grow, and optionally
// rescales its mesh in its own frame (factors > 0 per axis; unset = keep the current scale).
struct MoveObstacle {
  uint32_t obstacle = 0;
  RigidTransform worldFromLocal;
  std::optional<Vec3> scale;
};

// Imports a support mesh (a file env/mesh_import.h reads: .obj, .ply, .stl, .gltf, .glb,
// .fbx...) as a new obstacle the plants collide with and climb. A relative path is resolved
// against the scene's directory. A missing or bad file is an Error naming it.
struct AddObstacle {
  std::string path;
  std::string name;  // empty = the file's stem
  RigidTransform worldFromLocal;
  Vec3 scale = Vec3::Ones();                // applied to the mesh in its own frame
  Vec3 color = Vec3(0.6f, 0.6f, 0.6f);      // linear RGB, for rendering
};

// Replaces a light (by index): its position (point lights) and direction (directional).
struct MoveLight {
  uint32_t light = 0;
  env::Light value;
};

// Wind emitters (env::WindSettings::emitters; in sph mode they also feed the simulated air).
struct AddEmitter {
  env::WindEmitter emitter;
};
struct EditEmitter {
  uint32_t index = 0;
  env::WindEmitter emitter;
};
struct RemoveEmitter {
  uint32_t index = 0;
};

// Live species parameters of a particle plant: a JSON object of species keys (as in a species
// file, docs/particles.md), applied on top of the plant's current species.
struct SetSpecies {
  uint32_t plant = 0;
  Json keys = Json::object();
};

// A new grammar for an L-system plant (the studio's L-system editor): the grammar text
// replaces the plant's ("grammar_text" in its scene-file object; its "grammar" still names it
// and places relative textures), optionally with a new derivation length, and the plant is
// derived again from its seed to the derivation step it had reached. A grammar that does not
// compile is an Error at "/text line:col", and nothing changes.
struct SetGrammar {
  uint32_t plant = 0;
  std::string text;
  std::optional<int> derivationLength;
};

// A new p-graph for a component-graph plant (the studio's p-graph editor: parameters,
// components, links): the graph document (docs/graph-format.md) replaces the plant's
// ("graph_document" in its scene-file object; its "graph" still names it and places its
// relative files) and the plant is generated again at once. A graph that does not read is an
// Error at "/graph<pointer in the graph>", and nothing changes.
struct SetGraph {
  uint32_t plant = 0;
  Json graph = Json::object();
};

// Advances the simulation (not an undo entry of its own).
struct Step {
  uint32_t count = 1;
};

// Undo / redo as edits, so that scripts and the session journal replay them too.
struct Undo {};
struct Redo {};

using Edit = std::variant<SeedPlant, SeedBranch, Cut, DragBegin, DragMove, DragEnd, PaintStroke, MoveObstacle,
                          MoveLight, AddEmitter, EditEmitter, RemoveEmitter, SetSpecies, Step, Undo, Redo,
                          AddObstacle, SetGrammar, SetGraph>;

// The edit's JSON "edit" name, e.g. "seed_plant".
const char* editName(const Edit& edit);
// {"edit": "<name>", ...fields}.
Json editToJson(const Edit& edit);
// Reads an edit from an object whose "edit" key names its kind; strict (unknown keys are
// errors naming source and pointer). Does not call o.finish() for keys it does not know
// about beyond the edit's own: the caller may read more keys (e.g. "at_step") first.
Edit readEdit(JsonObject& o);

// An edit at a step of the script's clock: steps run since the script (or session) started,
// including those of Step edits; an undo does not turn it back.
struct TimedEdit {
  uint32_t atStep = 0;
  Edit edit;
};

// --- the editor ---

class Editor {
 public:
  static constexpr size_t kDefaultHistoryBytes = size_t(256) << 20;

  // `historyBytes` caps the memory of undo and redo snapshots; the oldest are dropped.
  explicit Editor(Session& session, size_t historyBytes = kDefaultHistoryBytes);
  ~Editor();
  Editor(const Editor&) = delete;
  Editor& operator=(const Editor&) = delete;

  Session& session() { return session_; }
  const Session& session() const { return session_; }

  // Applies an edit. Throws Error for an edit that does not fit the session (no such plant,
  // particle, obstacle...), leaving the session as it was. Undo/Redo with nothing to undo or
  // redo are Errors too.
  void apply(const Edit& edit);
  // Steps the session (same as apply(Step{count})).
  void step(uint32_t count = 1);

  bool canUndo() const;
  bool canRedo() const;
  void undo();  // throws Error when there is nothing to undo
  void redo();  // throws Error when there is nothing to redo
  size_t undoDepth() const;
  size_t redoDepth() const;
  size_t historyBytes() const;  // memory held by snapshots

  bool dragging() const { return dragging_; }
  // The drag gesture under way: the plant, the part held (models::Grip) and the strength, which
  // drag_move keeps.
  struct Drag {
    uint32_t plant = 0;
    uint32_t handle = kNoParticle;
    float strength = 0.0f;
  };
  const Drag& drag() const { return drag_; }

  // Steps run through this editor (step() and Step edits): the clock of the journal. Unlike
  // Session::stepCount() it never goes back (an undo rewinds the session's steps, not this).
  // Step the session through the editor so that the journal replays it.
  uint32_t stepsRun() const { return stepsRun_; }

  // Every applied edit, with the editor's clock (stepsRun()) when it was applied, in order
  // (steps are merged into one entry per run of steps). Replaying it with runEditScript on
  // the same starting session gives the same state.
  const std::vector<TimedEdit>& journal() const { return journal_; }
  // Continues an earlier journal (a loaded session file): the clock resumes at its end, and a
  // drag gesture the journal leaves under way is under way (dragging(), drag()).
  void setJournal(std::vector<TimedEdit> journal);

 private:
  struct Snapshot;
  void record(uint32_t at, const Edit& edit);
  void trim();

  Session& session_;
  size_t historyBytesCap_;
  std::vector<Snapshot> undo_, redo_;
  std::vector<TimedEdit> journal_;
  uint32_t stepsRun_ = 0;
  bool dragging_ = false;
  Drag drag_;
};

// --- picking ---

struct NodePick {
  uint32_t plant = 0;
  uint32_t node = 0;                 // node index in the plant's snapshot
  uint32_t particle = kNoParticle;   // the part's handle, for models that can be held (models::Grip)
  Vec3 point = Vec3::Zero();         // closest point on the segment's axis to the ray
  float t = 0.0f;                    // distance along the ray (m)
};

// The plant segment nearest the ray origin among those the ray passes within
// max(segment radius, tolerance) of. `dir` need not be unit length.
std::optional<NodePick> pickNode(const Session& session, const Vec3& origin, const Vec3& dir,
                                 float tolerance = 0.01f, float maxDistance = 1e4f);
// The first surface the ray hits (for seeding and painting): an obstacle's, or a support
// plant's stem (hit->onStem(); a climber seeded there climbs that plant).
std::optional<env::RayHit> pickSurface(const Session& session, const Vec3& origin, const Vec3& dir,
                                       float maxDistance = 1e4f);
// The direction a plant seeded where a ray of direction `dir` hit starts growing in: on an
// obstacle, its normal toward the ray's side; on a support plant's stem, up along the bark
// (the world's up in the stem's tangent plane, or the stem's own direction where that is
// nearly zero), so that a climber seeded on a trunk or a bough climbs it.
Vec3 seedDirection(const Session& session, const env::RayHit& hit, const Vec3& dir);

}  // namespace tendril::session
