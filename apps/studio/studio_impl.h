// The studio's state shared by studio.cpp (frame loop, viewport tools) and panels.cpp (the
// ImGui panels). Private to apps/studio.
#pragma once

#include "autosave.h"
#include "graph_panel.h"
#include "lsystem_panel.h"
#include "studio.h"

#include "tendril/core/triangle_mesh.h"
#include "tendril/session/edit.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/session.h"

#include <optional>
#include <unordered_map>
#include <string>
#include <vector>

namespace tendril::studio {

// A mouse gesture in the viewport with the left button, from press to release.
struct Gesture {
  bool active = false;
  Tool tool = Tool::View;
  Vec2 start = Vec2::Zero();
  Vec2 last = Vec2::Zero();
  // Drag and move obstacle: the grabbed point; paint: the stroke so far; move obstacle / light:
  // the preview.
  Vec3 anchor = Vec3::Zero();
  env::Stroke stroke;
  uint32_t obstacle = 0;
  RigidTransform original, preview;
  // Move obstacle with Ctrl: the scale before and during the gesture, and the obstacle's mesh
  // at the previewed scale (drawn instead of its own until the gesture ends).
  Vec3 originalScale = Vec3::Ones(), previewScale = Vec3::Ones();
  TriangleMesh currentMesh, previewMesh;
  uint32_t light = 0;
  env::Light lightPreview;
};

enum class FileAction { None, Open, Save, Export, Import };

struct Studio::Impl {
  explicit Impl(const StudioOptions& options);

  // studio.cpp
  int run();
  void openFile(const std::filesystem::path& path);
  void saveFile(const std::filesystem::path& path);
  void exportFile(const std::filesystem::path& path);
  // File > Import support mesh: the mesh as a new obstacle (an AddObstacle edit).
  void importMesh(const std::filesystem::path& path);
  // The autosave a session that did not exit cleanly left: opened as File > Open opens a
  // session (an Error is the status line; headless, it is thrown), or removed.
  void restoreAutosave();
  void discardAutosave();
  // Once a frame: the autosave, when due (not while the restore question is open or during a
  // gesture); an Error becomes the status line.
  void autosaveIfDue();
  // Applies an edit through the library's Editor; an Error becomes the status line.
  bool apply(const session::Edit& edit);
  void undo();
  void redo();
  void stepOnce();
  void simulate();
  void handleKeys();
  void handleViewportInput();
  void beginGesture(const Vec2& pixel);
  void moveGesture(const Vec2& pixel);
  void endGesture(const Vec2& pixel);
  void updateStress();
  void drawViewport();
  render::Ray rayAt(const Vec2& pixel) const;
  float pickTolerance() const;
  Vec2 viewportPixel(float x, float y) const;

  // panels.cpp
  void layout();
  void drawUi();
  void drawMenu();
  void drawTools();
  void drawToolOptions();
  void drawSceneTree();
  void drawInspector();
  void drawPlantPanel(uint32_t plant);
  void drawLiveSettings(uint32_t plant, const models::LiveSettings& settings);
  void drawObstaclePanel(uint32_t obstacle);
  void drawLightPanel(uint32_t light);
  void drawEmitterPanel(uint32_t emitter);
  void drawStrokePanel(uint32_t stroke);
  void drawWindPanel();
  void drawTimeline();
  void drawStatus();
  void drawFileDialog();
  void drawRestorePrompt();

  StudioOptions options;
  Window window;
  std::unique_ptr<render::Renderer> renderer;
  render::RenderSettings renderSettings;
  ViewportTarget target;
  std::unique_ptr<session::Session> session;
  std::unique_ptr<session::Editor> editor;
  std::optional<session::EditScript> script;
  size_t nextScriptEdit = 0;
  uint32_t scriptStart = 0;  // the editor's steps run when the script started
  std::filesystem::path currentPath;
  std::unique_ptr<Autosave> autosave;
  bool restorePending = false;  // the "Restore the session from ...?" dialog is open

  ViewportScene view;
  render::Camera camera;
  bool cameraFramed = false;
  int viewportWidth = 1, viewportHeight = 1;  // framebuffer pixels
  Rect viewport;                              // window units
  Selection selection;
  Tool tool = Tool::View;
  Gesture gesture;
  std::optional<uint32_t> dragPlant;  // the plant of the drag under way (interactive or scripted)
  bool playing = true;
  bool showAir = true;  // the simulated air's streaks (wind mode sph)
  bool sway = true;     // plants sway and their leaves move in the wind (wind panel)
  int speed = 1;
  bool meshesChanged = true;
  uint64_t obstacleRevision = 0;  // the session's when the viewport last fetched obstacle meshes
  FrameTiming timing;
  double lastStepMs = 0.0;
  uint64_t frameCount = 0;
  std::string status;
  bool statusIsError = false;
  // Plants that stopped growing early or stay small, and why (Session::reportGrowth), shown
  // under the status line; found again every kGrowthCheckSteps steps and when growth pauses.
  std::vector<session::Session::GrowthReport> growthProblems;
  uint32_t growthCheckedAt = 0;  // the editor's steps run when they were last found
  static constexpr uint32_t kGrowthCheckSteps = 20;
  void checkGrowth();

  // Tool settings.
  int seedModel = 0;  // index into kSeedModels
  std::string seedSpecies;
  uint64_t nextSeed = 1;
  float paintRadius = 0.15f;
  float paintStrength = 1.0f;
  float dragStrength = 0.5f;
  float emitterSpeed = 4.0f;
  float emitterRadius = 0.3f;

  // Panels.
  FileAction fileAction = FileAction::None;
  std::string filePath;
  Vec3 importPosition = Vec3::Zero();  // File > Import: where the mesh's origin goes (m)
  float importScale = 1.0f;
  LSystemPanel lsystemPanel;
  GraphPanel graphPanel;
};

inline constexpr const char* kSeedModels[] = {"particles", "climb", "lsystem", "graph"};

}  // namespace tendril::studio
