#include "studio.h"

#include "studio_impl.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/timer.h"
#include "tendril/io/image.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session_file.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <fmt/format.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

namespace tendril::studio {

const char* toolName(Tool tool) {
  switch (tool) {
    case Tool::View: return "View";
    case Tool::Seed: return "Seed plant";
    case Tool::BranchSeed: return "Branch seed";
    case Tool::Cut: return "Cut";
    case Tool::Drag: return "Drag";
    case Tool::PaintAttract: return "Paint attract";
    case Tool::PaintRepel: return "Paint repel";
    case Tool::MoveObstacle: return "Move obstacle";
    case Tool::Light: return "Light";
    case Tool::WindEmitter: return "Wind emitter";
  }
  return "?";
}

Studio::Impl::Impl(const StudioOptions& o) : options(o), window(o.width, o.height, "Tendril Studio") {
  renderer = std::make_unique<render::Renderer>();
  renderSettings.shadowMapSize = 1024;
  speed = o.speed;
  playing = !o.paused;
  sway = o.sway;
  openFile(o.input.empty() ? std::filesystem::path(TENDRIL_EXAMPLES_DIR) / "scenes/default.json"
                           : std::filesystem::path(o.input));
  // The autosave: headless runs (tests, scripts) have none unless asked, so that they leave
  // nothing behind and do not meet each other's.
  AutosaveSettings autosaveSettings;
  if (!o.autosave.empty() && o.autosave != "off") autosaveSettings.path = o.autosave;
  else if (o.autosave.empty() && !o.headless()) autosaveSettings.path = defaultAutosavePath();
  autosaveSettings.intervalSeconds = o.autosaveInterval;
  autosaveSettings.edits = o.autosaveEdits;
  autosave = std::make_unique<Autosave>(std::move(autosaveSettings));
  autosave->reset(*editor);
  if (!autosave->message().empty()) {
    log::warn("{}", autosave->message());
    status = autosave->message();
    statusIsError = true;
  }
  if (autosave->leftover()) {
    log::info("{}: an autosave from {} of a session that did not exit cleanly", autosave->path().string(),
              autosave->leftoverTime());
    // Answered before the script is loaded: it replays on the restored session.
    if (o.restoreAutosave == "yes") restoreAutosave();
    else if (o.restoreAutosave == "no") discardAutosave();
    else restorePending = true;
  }
  if (!o.select.empty()) {
    const size_t colon = o.select.find(':');
    const std::string kind = o.select.substr(0, colon);
    const uint32_t index = uint32_t(std::stoul(o.select.substr(colon + 1)));
    selection.kind = kind == "plant"      ? Selection::Kind::Plant
                     : kind == "obstacle" ? Selection::Kind::Obstacle
                     : kind == "light"    ? Selection::Kind::Light
                     : kind == "emitter"  ? Selection::Kind::Emitter
                                          : Selection::Kind::Stroke;
    selection.index = index;
  }
  if (!o.script.empty()) {
    script = session::loadEditScript(o.script);
    scriptStart = editor->stepsRun();
  }
}

void Studio::Impl::openFile(const std::filesystem::path& path) {
  std::unique_ptr<session::Session> opened;
  std::vector<session::TimedEdit> journal;
  if (session::isSessionFile(path)) {
    session::LoadedSession loaded = session::loadSession(path);
    opened = std::move(loaded.session);
    journal = std::move(loaded.journal);
  } else {
    opened = session::Session::open(path);
  }
  editor.reset();
  session = std::move(opened);
  editor = std::make_unique<session::Editor>(*session);
  editor->setJournal(std::move(journal));
  // A session saved while a part was being dragged: no mouse holds it here, so the gesture ends
  // (journaled, so the journal still replays).
  if (editor->dragging()) editor->apply(session::DragEnd{});
  if (autosave) autosave->reset(*editor);
  currentPath = path;
  selection = {};
  gesture = {};
  dragPlant.reset();
  script.reset();  // a script replays on the session it was started with
  nextScriptEdit = 0;
  lsystemPanel.close();
  graphPanel.close();
  meshesChanged = true;
  obstacleRevision = session->obstacleRevision();
  cameraFramed = false;
  view.stopSway();
  nextSeed = session->plantCount() + 1;
  status = fmt::format("opened {}", path.string());
  statusIsError = false;
}

void Studio::Impl::restoreAutosave() {
  const std::string when = autosave->leftoverTime();
  autosave->restored();
  try {
    openFile(autosave->path());
  } catch (const Error& e) {
    if (options.headless()) throw;
    status = fmt::format("cannot restore the autosave: {}", e.what());
    statusIsError = true;
    return;
  }
  // Saving goes to a file of the user's choosing, not over the autosave (a clean exit removes it).
  currentPath.clear();
  status = fmt::format("restored the session autosaved at {}", when);
  statusIsError = false;
  log::info("{} ({})", status, autosave->path().string());
}

void Studio::Impl::discardAutosave() {
  status = fmt::format("discarded the session autosaved at {}", autosave->leftoverTime());
  statusIsError = false;
  autosave->discard();
  log::info("{} ({})", status, autosave->path().string());
}

void Studio::Impl::autosaveIfDue() {
  if (restorePending || gesture.active || editor->dragging()) return;
  try {
    if (autosave->update(*session, *editor))
      log::info("autosaved {} (step {})", autosave->path().string(), session->stepCount());
  } catch (const Error& e) {
    status = fmt::format("autosave: {}", e.what());
    statusIsError = true;
    log::warn("{}", status);
  }
}

void Studio::Impl::saveFile(const std::filesystem::path& path) {
  session::saveSession(path, *session, editor->journal());
  currentPath = path;
  status = fmt::format("saved {}", path.string());
  statusIsError = false;
}

void Studio::Impl::exportFile(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext != ".glb" && ext != ".obj") throw Error(path.string(), "", "expected a .glb or .obj file name");
  // Through what `tendril grow` writes with (session::writePlantFiles): the scene's output
  // settings — radial segments, subdivisions, the obstacles when it asks for them, levels of
  // detail, leaf atlas, impostor, maps, engine wind data and the Pivot Painter textures beside
  // the .glb.
  io::ExportScene scene;
  const std::vector<std::string> files =
      session::writePlantFiles(*session, path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path(),
                               path.stem().string(), {ext.substr(1)}, session->scene().source, scene);
  status = fmt::format("exported {} plant(s) to {}", scene.plants.size(), fmt::join(files, ", "));
  statusIsError = false;
}

void Studio::Impl::importMesh(const std::filesystem::path& path) {
  session::AddObstacle edit;
  // The path box is relative to the working directory; edits resolve against the scene's.
  edit.path = std::filesystem::absolute(path).lexically_normal().string();
  edit.worldFromLocal.translation = importPosition;
  edit.scale = Vec3::Constant(importScale);
  editor->apply(edit);  // an Error (the file's) reaches the dialog
  selection = {Selection::Kind::Obstacle, uint32_t(session->environment().obstacleCount() - 1), std::nullopt};
  status = fmt::format("imported {} as obstacle {}", path.string(), selection.index);
  statusIsError = false;
}

bool Studio::Impl::apply(const session::Edit& edit) {
  try {
    editor->apply(edit);
    if (!std::holds_alternative<session::DragMove>(edit) && !std::holds_alternative<session::Step>(edit)) {
      status = session::editName(edit);
      statusIsError = false;
    }
    return true;
  } catch (const Error& e) {
    status = e.what();
    statusIsError = true;
    return false;
  } catch (const std::exception& e) {
    status = fmt::format("{}: {}", session::editName(edit), e.what());
    statusIsError = true;
    return false;
  }
}

void Studio::Impl::undo() {
  if (editor->dragging() || !editor->canUndo()) return;
  apply(session::Undo{});
}

void Studio::Impl::redo() {
  if (editor->dragging() || !editor->canRedo()) return;
  apply(session::Redo{});
}

void Studio::Impl::stepOnce() {
  Timer timer;
  editor->step(1);
  lastStepMs = timer.milliseconds();
}

// One frame of simulation: `speed` steps, with the script's edits applied at their steps by
// the library's runner (one call per frame, for the edits that fall within it).
void Studio::Impl::simulate() {
  Timer timer;
  if (playing) {
    if (script && (nextScriptEdit < script->edits.size())) {
      // The script's clock is the editor's (steps run; an undo does not turn it back).
      const uint32_t done = editor->stepsRun() - scriptStart;
      const size_t first = nextScriptEdit;
      session::EditScript chunk;
      chunk.source = script->source;
      while (nextScriptEdit < script->edits.size() && script->edits[nextScriptEdit].atStep <= done + uint32_t(speed)) {
        session::TimedEdit e = script->edits[nextScriptEdit++];
        e.atStep = e.atStep > done ? e.atStep - done : 0;
        chunk.edits.push_back(std::move(e));
      }
      for (const session::TimedEdit& e : chunk.edits)
        if (const auto* drag = std::get_if<session::DragBegin>(&e.edit)) dragPlant = drag->plant;
      try {
        session::runEditScript(*editor, chunk, uint32_t(speed));
      } catch (const Error& e) {
        // Name the edit by its place in the whole script, not in this frame's part of it.
        std::string location = e.location();
        if (location.rfind("/edits/", 0) == 0)
          location = fmt::format("/edits/{}", first + std::stoul(location.substr(7)));
        Error named(e.source(), location, e.message());
        if (options.headless()) throw named;
        status = named.what();
        statusIsError = true;
        script.reset();
      }
    } else {
      editor->step(uint32_t(speed));
    }
  }
  timing.simulation = timer.milliseconds();
  if (playing && speed > 0) lastStepMs = timing.simulation / speed;
  checkGrowth();
}

void Studio::Impl::checkGrowth() {
  const uint32_t run = editor->stepsRun();
  if (run == growthCheckedAt) return;
  const bool paused = !playing || session->finished();
  if (!paused && run < growthCheckedAt + kGrowthCheckSteps && run > growthCheckedAt) return;
  growthCheckedAt = run;
  growthProblems = session->reportGrowth();
}

// Six pixels at the depth of the camera's target, in metres: how close to a thin branch the
// cursor must come to pick it.
float Studio::Impl::pickTolerance() const {
  return 6.0f * 2.0f * camera.distance() * std::tan(0.5f * camera.fovY) / float(std::max(1, viewportHeight));
}

render::Ray Studio::Impl::rayAt(const Vec2& pixel) const {
  return render::pixelRay(camera, viewportWidth, viewportHeight, pixel);
}

Vec2 Studio::Impl::viewportPixel(float x, float y) const {
  const float s = window.contentScale();
  return Vec2((x - viewport.x) * s, (y - viewport.y) * s);
}

void Studio::Impl::handleKeys() {
  ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput || restorePending) return;
  const bool ctrl = io.KeyCtrl;
  if (ctrl && ImGui::IsKeyPressed(GLFW_KEY_Z, false)) {
    if (io.KeyShift) redo();
    else undo();
  }
  if (ctrl && ImGui::IsKeyPressed(GLFW_KEY_Y, false)) redo();
  if (ctrl && ImGui::IsKeyPressed(GLFW_KEY_S, false)) {
    fileAction = FileAction::Save;
    filePath = currentPath.extension() == ".tses" ? currentPath.string() : "session.tses";
  }
  if (ctrl && ImGui::IsKeyPressed(GLFW_KEY_O, false)) {
    fileAction = FileAction::Open;
    filePath = currentPath.string();
  }
  if (ctrl && ImGui::IsKeyPressed(GLFW_KEY_Q, false)) window.requestClose();
  if (ctrl) return;
  if (ImGui::IsKeyPressed(GLFW_KEY_SPACE, false)) playing = !playing;
  if (ImGui::IsKeyPressed(GLFW_KEY_PERIOD)) stepOnce();
  if (ImGui::IsKeyPressed(GLFW_KEY_F, false)) cameraFramed = false;
  if (ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) tool = Tool::View;
  const Tool keys[] = {Tool::View, Tool::Seed, Tool::BranchSeed, Tool::Cut, Tool::Drag,
                       Tool::PaintAttract, Tool::PaintRepel, Tool::MoveObstacle, Tool::Light, Tool::WindEmitter};
  for (int k = 0; k < 10; ++k)
    if (ImGui::IsKeyPressed(GLFW_KEY_1 + (k == 9 ? -1 : k), false)) tool = keys[k];
}

void Studio::Impl::handleViewportInput() {
  ImGuiIO& io = ImGui::GetIO();
  const ImVec2 mouse = io.MousePos;
  const Vec2 pixel = viewportPixel(mouse.x, mouse.y);
  if (gesture.active) {
    if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
      if ((pixel - gesture.last).squaredNorm() > 0.0f) moveGesture(pixel);
    } else {
      endGesture(pixel);
    }
    return;
  }
  if (io.WantCaptureMouse || !viewport.contains(mouse.x, mouse.y)) return;
  const float scale = 1.0f / std::max(1.0f, viewport.h);
  const bool leftOrbits = tool == Tool::View;
  const bool orbitDrag = ImGui::IsMouseDragging(ImGuiMouseButton_Right, 0.0f) ||
                         (leftOrbits && ImGui::IsMouseDragging(ImGuiMouseButton_Left, 0.0f));
  if (orbitDrag && !io.KeyShift) {
    camera = render::orbit(camera, -io.MouseDelta.x * scale * 3.0f, io.MouseDelta.y * scale * 3.0f);
  } else if (ImGui::IsMouseDragging(ImGuiMouseButton_Middle, 0.0f) || (orbitDrag && io.KeyShift)) {
    camera = render::pan(camera, -io.MouseDelta.x * scale, io.MouseDelta.y * scale);
  }
  if (io.MouseWheel != 0.0f) camera = render::zoom(camera, std::pow(0.85f, io.MouseWheel));
  if (!leftOrbits && ImGui::IsMouseClicked(ImGuiMouseButton_Left)) beginGesture(pixel);
  if (leftOrbits && ImGui::IsMouseClicked(ImGuiMouseButton_Left) && io.MouseClickedCount[0] == 2) {
    // Double click selects what is under the cursor.
    render::Ray ray = rayAt(pixel);
    if (auto node = session::pickNode(*session, ray.origin, ray.direction, pickTolerance(), camera.far))
      selection = {Selection::Kind::Plant, node->plant, node->node};
    else if (auto hit = session::pickSurface(*session, ray.origin, ray.direction, camera.far); hit && !hit->onStem())
      selection = {Selection::Kind::Obstacle, hit->obstacle, std::nullopt};
  }
}

void Studio::Impl::beginGesture(const Vec2& pixel) {
  render::Ray ray = rayAt(pixel);
  gesture = {};
  gesture.tool = tool;
  gesture.start = gesture.last = pixel;
  switch (tool) {
    case Tool::View: return;
    case Tool::Seed: {
      auto hit = session::pickSurface(*session, ray.origin, ray.direction, camera.far);
      if (!hit) {
        status = "seed: click on a surface";
        return;
      }
      session::SeedPlant seed;
      seed.model = kSeedModels[seedModel];
      seed.species = seedSpecies;
      seed.position = hit->point;
      seed.normal = session::seedDirection(*session, *hit, ray.direction);
      seed.seed = nextSeed++;
      if (apply(seed)) selection = {Selection::Kind::Plant, uint32_t(session->plantCount() - 1), std::nullopt};
      return;
    }
    case Tool::BranchSeed:
    case Tool::Cut:
    case Tool::Drag: {
      auto node = session::pickNode(*session, ray.origin, ray.direction, pickTolerance(), camera.far);
      if (!node) {
        status = fmt::format("{}: click on a branch", toolName(tool));
        return;
      }
      selection = {Selection::Kind::Plant, node->plant, node->node};
      if (tool == Tool::Cut) {
        apply(session::Cut{node->plant, node->node});
        return;
      }
      if (node->particle == session::kNoParticle) {
        status = fmt::format("{}: plants of model \"{}\" cannot be held", toolName(tool),
                             session->plantSpec(node->plant).model);
        statusIsError = true;
        return;
      }
      if (tool == Tool::BranchSeed) {
        // Sideways from the segment, toward the viewer, leaning forward along it.
        if (node->plant >= view.plants().size() || node->node >= view.plants()[node->plant].nodeCount()) return;
        const plant::PlantModel& m = view.plants()[node->plant];
        Vec3 axis = m.orientation[node->node] * Vec3::UnitY();
        Vec3 side = -ray.direction - axis * axis.dot(-ray.direction);
        if (side.squaredNorm() < 1e-8f) side = m.orientation[node->node] * Vec3::UnitZ();
        Vec3 direction = (side.normalized() + 0.5f * axis).normalized();
        apply(session::SeedBranch{node->plant, node->particle, direction});
        return;
      }
      if (apply(session::DragBegin{node->plant, node->particle, node->point, dragStrength})) {
        dragPlant = node->plant;
        gesture.active = true;
        gesture.anchor = node->point;
      }
      return;
    }
    case Tool::PaintAttract:
    case Tool::PaintRepel: {
      gesture.active = true;
      gesture.stroke.attract = tool == Tool::PaintAttract;
      gesture.stroke.radius = paintRadius;
      gesture.stroke.strength = paintStrength;
      moveGesture(pixel);
      return;
    }
    case Tool::MoveObstacle: {
      auto hit = session::pickSurface(*session, ray.origin, ray.direction, camera.far);
      if (!hit) return;
      if (hit->onStem()) {
        status = "move obstacle: that is a plant's stem, not an obstacle";
        return;
      }
      selection = {Selection::Kind::Obstacle, hit->obstacle, std::nullopt};
      gesture.active = true;
      gesture.obstacle = hit->obstacle;
      gesture.anchor = hit->point;
      gesture.original = gesture.preview = session->environment().obstacle(hit->obstacle).worldFromLocal;
      gesture.originalScale = gesture.previewScale = session->obstacleScale(hit->obstacle);
      return;
    }
    case Tool::Light: {
      const auto& lights = session->environment().lights();
      if (lights.empty()) {
        status = "light: the scene has no lights";
        return;
      }
      uint32_t index = selection.kind == Selection::Kind::Light && selection.index < lights.size() ? selection.index : 0;
      selection = {Selection::Kind::Light, index, std::nullopt};
      gesture.active = true;
      gesture.light = index;
      gesture.lightPreview = lights[index];
      return;
    }
    case Tool::WindEmitter: {
      auto hit = session::pickSurface(*session, ray.origin, ray.direction, camera.far);
      if (!hit) {
        status = "wind emitter: click on a surface to blow at";
        return;
      }
      Vec3 normal = hit->normal.dot(ray.direction) > 0.0f ? Vec3(-hit->normal) : hit->normal;
      env::WindEmitter emitter;
      emitter.position = hit->point + normal * 1.0f;
      emitter.direction = -normal;
      emitter.speed = emitterSpeed;
      emitter.radius = emitterRadius;
      emitter.reach = 4.0f;
      if (apply(session::AddEmitter{emitter}))
        selection = {Selection::Kind::Emitter,
                     uint32_t(session->environment().windField().settings().emitters.size() - 1), std::nullopt};
      return;
    }
  }
}

void Studio::Impl::moveGesture(const Vec2& pixel) {
  const Vec2 delta = pixel - gesture.last;
  gesture.last = pixel;
  render::Ray ray = rayAt(pixel);
  switch (gesture.tool) {
    case Tool::Drag:
      apply(session::DragMove{dragPoint(camera, viewportWidth, viewportHeight, pixel, gesture.anchor)});
      return;
    case Tool::PaintAttract:
    case Tool::PaintRepel: {
      auto hit = session::pickSurface(*session, ray.origin, ray.direction, camera.far);
      if (!hit) return;
      auto& points = gesture.stroke.points;
      if (points.empty() || (points.back() - hit->point).norm() > 0.3f * gesture.stroke.radius)
        points.push_back(hit->point);
      return;
    }
    case Tool::MoveObstacle: {
      Vec3 a = dragPoint(camera, viewportWidth, viewportHeight, gesture.start, gesture.anchor);
      Vec3 b = dragPoint(camera, viewportWidth, viewportHeight, pixel, gesture.anchor);
      gesture.preview = gesture.original;
      gesture.previewScale = gesture.originalScale;
      if (ImGui::GetIO().KeyCtrl) {
        // Ctrl: scale about the obstacle's own origin, doubling per half viewport height upward.
        const float factor = std::exp2((gesture.start.y() - pixel.y()) / float(std::max(1, viewportHeight)) * 2.0f);
        gesture.previewScale = (gesture.originalScale * factor).cwiseMax(Vec3::Constant(1e-4f)).cwiseMin(Vec3::Constant(1e4f));
        if (gesture.currentMesh.positions.empty()) gesture.currentMesh = session->environment().obstacleMesh(gesture.obstacle);
        gesture.previewMesh = gesture.currentMesh;
        const Vec3 ratio = gesture.previewScale.cwiseQuotient(gesture.originalScale);
        for (Vec3& v : gesture.previewMesh.positions) v = v.cwiseProduct(ratio);
      } else if (ImGui::GetIO().KeyShift) {
        // Shift: turn about the vertical axis through the grabbed point.
        float angle = (pixel.x() - gesture.start.x()) / float(std::max(1, viewportHeight)) * kPi;
        Quat turn(Eigen::AngleAxisf(angle, Vec3::UnitY()));
        gesture.preview.rotation = turn * gesture.original.rotation;
        gesture.preview.translation = turn * (gesture.original.translation - gesture.anchor) + gesture.anchor;
      } else {
        gesture.preview.translation = gesture.original.translation + (b - a);
      }
      return;
    }
    case Tool::Light: {
      env::Light& l = gesture.lightPreview;
      const float k = 3.0f / float(std::max(1, viewportHeight));
      if (l.type == env::Light::Type::Directional) {
        Quat yaw(Eigen::AngleAxisf(delta.x() * k, Vec3::UnitY()));
        Vec3 d = yaw * l.direction;
        Vec3 axis = d.cross(Vec3::UnitY());
        if (axis.squaredNorm() > 1e-8f) {
          Vec3 pitched = Eigen::AngleAxisf(-delta.y() * k, axis.normalized()) * d;
          if (pitched.y() < -0.02f) d = pitched;  // keep it shining downward
        }
        l.direction = d.normalized();
      } else {
        l.position = dragPoint(camera, viewportWidth, viewportHeight, pixel, l.position);
      }
      return;
    }
    default: return;
  }
}

void Studio::Impl::endGesture(const Vec2& pixel) {
  Gesture g = gesture;
  gesture.active = false;
  switch (g.tool) {
    case Tool::Drag:
      apply(session::DragEnd{});
      return;
    case Tool::PaintAttract:
    case Tool::PaintRepel:
      if (!g.stroke.points.empty()) apply(session::PaintStroke{g.stroke});
      return;
    case Tool::MoveObstacle:
      if (g.previewScale != g.originalScale)
        apply(session::MoveObstacle{g.obstacle, g.original, g.previewScale});
      else if ((g.preview.translation - g.original.translation).norm() > 0.0f ||
               !g.preview.rotation.isApprox(g.original.rotation))
        apply(session::MoveObstacle{g.obstacle, g.preview, std::nullopt});
      return;
    case Tool::Light:
      apply(session::MoveLight{g.light, g.lightPreview});
      return;
    default: return;
  }
}

// Stress colours of the plant being dragged (seed 000 fig. 6): exactly the strain breaking
// compares with its threshold — each segment's connection to its parent as the model's breaking
// rule measures it (models::StrainGauge, as a fraction of the strain at which it breaks), so
// red is where a connection breaks. Strain growth left before the drag shows too: breaking
// counts it just the same.
void Studio::Impl::updateStress() {
  if (!editor->dragging() || !dragPlant) {
    if (dragPlant) view.setStress(*dragPlant, {});
    dragPlant.reset();
    return;
  }
  const uint32_t plant = *dragPlant;
  const auto& plants = view.plants();
  if (plant >= plants.size() || plant >= session->plantCount()) return;
  const models::StrainGauge* gauge = std::as_const(session->system(plant)).strainGauge();
  if (!gauge) return;
  const std::vector<models::StrainGauge::NodeStrain> strain = gauge->nodeStrain(session->indexInSystem(plant));
  std::vector<float> stress(plants[plant].nodeCount(), 0.0f);
  for (size_t n = 0; n < strain.size() && n < stress.size(); ++n) {
    const models::StrainGauge::NodeStrain& s = strain[n];
    if (s.handle == models::kNoHandle) continue;
    stress[n] = std::clamp(s.strain, 0.0f, 1.0f);
  }
  view.setStress(plant, std::move(stress));
}

void Studio::Impl::drawViewport() {
  const float s = window.contentScale();
  viewportWidth = std::max(16, int(viewport.w * s));
  viewportHeight = std::max(16, int(viewport.h * s));
  if (!cameraFramed) {
    camera = render::defaultCamera(view.scene(), float(viewportWidth) / float(viewportHeight));
    cameraFramed = true;
  }
  render::RenderScene& scene = view.mutableScene();
  // Gesture previews: the obstacle or light where it will go, the stroke being painted.
  if (gesture.active && gesture.tool == Tool::MoveObstacle && gesture.obstacle < scene.obstacles.size()) {
    scene.obstacles[gesture.obstacle].worldFromLocal = gesture.preview;
    if (gesture.previewScale != gesture.originalScale) {
      scene.obstacles[gesture.obstacle].mesh = &gesture.previewMesh;
      scene.obstacles[gesture.obstacle].meshKey = 0;  // changes while the gesture goes on
    }
  }
  if (gesture.active && gesture.tool == Tool::Light && gesture.light < scene.lights.size())
    scene.lights[gesture.light] = gesture.lightPreview;
  if (gesture.active && !gesture.stroke.points.empty()) scene.strokes.push_back(gesture.stroke);
  if (const plant::PlantModel* preview = lsystemPanel.preview()) {
    render::PlantView pv;
    pv.model = preview;
    pv.selected = {0, uint32_t(preview->nodeCount())};
    scene.plants.push_back(pv);
  }
  target.bind(viewportWidth, viewportHeight);
  renderer->render(scene, camera, renderSettings, viewportWidth, viewportHeight);
  target.blitToWindow(int(viewport.x * s), int(viewport.y * s), window.framebufferHeight());
}

int Studio::Impl::run() {
  const bool headless = options.headless();
  int64_t framesLeft = options.frames;
  if (options.stats) std::printf("%s\n", window.glDescription().c_str());
  while (!window.shouldClose()) {
    Timer frameTimer;
    window.beginFrame();
    const bool lastFrame = headless && framesLeft <= 1;
    if (!headless || framesLeft > 0) simulate();
    else timing.simulation = 0.0;
    if (headless) --framesLeft;

    // Input first, so that the panels below see the session as the viewport draws it.
    layout();
    handleKeys();
    handleViewportInput();
    Timer updateTimer;
    if (session->obstacleRevision() != obstacleRevision) {  // imported, rescaled, or undone
      meshesChanged = true;
      obstacleRevision = session->obstacleRevision();
    }
    view.update(*session, selection, meshesChanged, showAir);
    // Wind motion on the clock of the frames (1/60 s each, so headless runs are reproducible).
    if (sway) view.sway(*session, float(frameCount) / 60.0f, 1.0f / 60.0f);
    else view.stopSway();
    meshesChanged = false;
    updateStress();
    view.applyStress();
    const double sceneMs = updateTimer.milliseconds();
    drawUi();

    Timer drawTimer;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, window.framebufferWidth(), window.framebufferHeight());
    glClearColor(0.1f, 0.1f, 0.11f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    drawViewport();
    window.renderUi();
    glFinish();
    const render::FrameStats& fs = renderer->lastFrame();
    timing.update = sceneMs + fs.buildMs + fs.uploadMs;
    timing.draw = drawTimer.milliseconds() - fs.buildMs - fs.uploadMs;
    if (lastFrame) {
      io::writePng(window.readBackBuffer(), options.screenshot);
      if (!options.saveSession.empty()) saveFile(options.saveSession);
      if (!options.exportPath.empty()) exportFile(options.exportPath);
    }
    window.swap();
    timing.frame = frameTimer.milliseconds();
    if (options.stats) {
      std::printf("frame %llu: step %u, %zu plants, %zu segments, simulation %.2f ms, update %.2f ms "
                  "(snapshots %.2f, instances %.2f, upload %.2f), draw %.2f ms, frame %.2f ms\n",
                  (unsigned long long)frameCount, session->stepCount(), session->plantCount(),
                  session->segmentCount(), timing.simulation, timing.update, view.snapshotMs(), fs.buildMs,
                  fs.uploadMs, timing.draw, timing.frame);
      std::fflush(stdout);
    }
    ++frameCount;
    autosaveIfDue();
    if (lastFrame) break;
  }
  // A clean exit: nothing to restore next time.
  autosave->finish();
  if (headless) {
    if (script && nextScriptEdit < script->edits.size())
      log::warn("{}: {} edit(s) at steps past the last frame were not applied", script->source,
                script->edits.size() - nextScriptEdit);
    log::info("wrote {} after {} frame(s), step {}, {} segments", options.screenshot, options.frames,
              session->stepCount(), session->segmentCount());
  }
  return 0;
}

Studio::Studio(const StudioOptions& options) : impl_(std::make_unique<Impl>(options)) {}
Studio::~Studio() = default;
int Studio::run() { return impl_->run(); }

}  // namespace tendril::studio
