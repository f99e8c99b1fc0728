// The studio's ImGui panels: menu, tools, scene tree, inspector (plant species, L-system
// editor, obstacle, light, emitter, stroke, wind), timeline and status bar. Every change to
// the session goes through Studio::Impl::apply (the library's Editor), so it can be undone.
#include "studio_impl.h"

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/graph/graph_model.h"
#include "tendril/lsystem/lsystem_model.h"
#include "tendril/core/schema.h"
#include "tendril/scene/settings_schema.h"

#include <fmt/format.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>

namespace tendril::studio {
namespace {

constexpr float kLeftWidth = 290.0f;
constexpr float kRightWidth = 380.0f;
constexpr float kTimelineHeight = 40.0f;
constexpr float kStatusHeight = 26.0f;
constexpr ImGuiWindowFlags kFixed = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize |
                                    ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoSavedSettings;

Vec3 degreesFromQuat(const Quat& q) {
  // X, then Y, then Z (as quatFromEulerDegrees): q = Rz · Ry · Rx.
  Mat3 r = q.toRotationMatrix();
  float y = std::asin(std::clamp(-r(2, 0), -1.0f, 1.0f));
  float x = std::atan2(r(2, 1), r(2, 2));
  float z = std::atan2(r(1, 0), r(0, 0));
  return Vec3(x, y, z) * (180.0f / kPi);
}

bool editVec3(const char* label, Vec3& v, float speed, const char* format = "%.3f") {
  // Within the world the readers accept (100 km of the origin; typed values are clamped too).
  const float extent = float(JsonObject::kWorldExtent);
  float values[3] = {v.x(), v.y(), v.z()};
  ImGui::DragFloat3(label, values, speed, -extent, extent, format, ImGuiSliderFlags_AlwaysClamp);
  v = Vec3(values[0], values[1], values[2]);
  return ImGui::IsItemDeactivatedAfterEdit();
}

// A slider for one number of a settings description (scene/settings_schema.h,
// particles/species_schema.h): its label, unit and range come from there. The value follows
// the slider; the result says when an edit was finished. `clamp`: typed values stay within the
// slider's range too (else they may go beyond, and the edit checks them).
template <class T>
bool fieldSlider(const schema::Field<T>& f, T& v, const char* format = "%.3f", bool clamp = true) {
  const std::string label = f.labelWithUnit();
  const ImGuiSliderFlags flags = clamp ? ImGuiSliderFlags_AlwaysClamp : ImGuiSliderFlags_None;
  if (f.kind == schema::Kind::Integer) {
    int x = int(schema::fileValue(f, v));
    ImGui::SliderInt(label.c_str(), &x, int(f.sliderLow()), int(f.sliderHigh()), "%d", flags);
    schema::setFileValue(f, v, x);
  } else {
    const float shown = float(schema::fileValue(f, v));
    float x = shown;
    ImGui::SliderFloat(label.c_str(), &x, float(f.sliderLow()), float(f.sliderHigh()), format, flags);
    if (x != shown) schema::setFileValue(f, v, x);  // an untouched angle keeps its bits
  }
  return ImGui::IsItemDeactivatedAfterEdit();
}

// The label of a field, with its unit, for widgets that are not sliders.
template <class T>
std::string fieldLabel(const schema::Schema<T>& s, std::string_view key) {
  return s.at(key).labelWithUnit();
}

}  // namespace

void Studio::Impl::layout() {
  ImGuiIO& io = ImGui::GetIO();
  const float menu = ImGui::GetFrameHeight();
  viewport = {kLeftWidth, menu, std::max(16.0f, io.DisplaySize.x - kLeftWidth - kRightWidth),
              std::max(16.0f, io.DisplaySize.y - menu - kTimelineHeight - kStatusHeight)};
}

void Studio::Impl::drawUi() {
  drawMenu();
  ImGuiIO& io = ImGui::GetIO();
  const float menu = ImGui::GetFrameHeight();
  const float bottom = io.DisplaySize.y - kTimelineHeight - kStatusHeight;

  ImGui::SetNextWindowPos(ImVec2(0, menu));
  ImGui::SetNextWindowSize(ImVec2(kLeftWidth, bottom - menu));
  if (ImGui::Begin("Scene", nullptr, kFixed)) {
    drawTools();
    drawToolOptions();
    ImGui::Separator();
    drawSceneTree();
  }
  ImGui::End();

  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - kRightWidth, menu));
  ImGui::SetNextWindowSize(ImVec2(kRightWidth, bottom - menu));
  if (ImGui::Begin("Inspector", nullptr, kFixed)) {
    drawInspector();
    ImGui::Spacing();
    drawWindPanel();
  }
  ImGui::End();

  ImGui::SetNextWindowPos(ImVec2(0, bottom));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, kTimelineHeight));
  if (ImGui::Begin("Timeline", nullptr, kFixed | ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoScrollbar))
    drawTimeline();
  ImGui::End();

  ImGui::SetNextWindowPos(ImVec2(0, io.DisplaySize.y - kStatusHeight));
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, kStatusHeight));
  ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(8, 4));
  if (ImGui::Begin("Status", nullptr, kFixed | ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoScrollbar))
    drawStatus();
  ImGui::End();
  ImGui::PopStyleVar();
  drawFileDialog();
  drawRestorePrompt();
}

void Studio::Impl::drawMenu() {
  if (!ImGui::BeginMainMenuBar()) return;
  if (ImGui::BeginMenu("File")) {
    if (ImGui::MenuItem("Open scene or session...", "Ctrl+O")) {
      fileAction = FileAction::Open;
      filePath = currentPath.string();
    }
    if (ImGui::MenuItem("Save session...", "Ctrl+S")) {
      fileAction = FileAction::Save;
      filePath = currentPath.extension() == ".tses" ? currentPath.string() : "session.tses";
    }
    if (ImGui::MenuItem("Export plants (.glb / .obj)...")) {
      fileAction = FileAction::Export;
      filePath = "plants.glb";
    }
    if (ImGui::MenuItem("Import support mesh...")) {
      fileAction = FileAction::Import;
      filePath.clear();
      importPosition = camera.target;
      importScale = 1.0f;
    }
    ImGui::Separator();
    if (ImGui::MenuItem("Quit", "Ctrl+Q")) window.requestClose();
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Edit")) {
    if (ImGui::MenuItem("Undo", "Ctrl+Z", false, editor->canUndo() && !editor->dragging())) undo();
    if (ImGui::MenuItem("Redo", "Ctrl+Y", false, editor->canRedo() && !editor->dragging())) redo();
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("View")) {
    if (ImGui::MenuItem("Frame scene", "F")) cameraFramed = false;
    ImGui::MenuItem("Shadows", nullptr, &renderSettings.shadows);
    ImGui::EndMenu();
  }
  ImGui::EndMainMenuBar();
}

void Studio::Impl::drawFileDialog() {
  static const char* titles[] = {"", "Open", "Save session", "Export plants", "Import support mesh"};
  if (fileAction == FileAction::None) return;
  const char* title = titles[int(fileAction)];
  if (!ImGui::IsPopupOpen(title)) ImGui::OpenPopup(title);
  ImGui::SetNextWindowSize(ImVec2(520, 0));
  if (ImGui::BeginPopupModal(title, nullptr, ImGuiWindowFlags_NoSavedSettings)) {
    ImGui::TextUnformatted(fileAction == FileAction::Open     ? "Scene (.json) or session (.tses) file:"
                           : fileAction == FileAction::Save   ? "Session file (.tses):"
                           : fileAction == FileAction::Import ? "Mesh file (.obj, .glb, .gltf, .ply, .stl, .fbx...):"
                                                              : "Plants file (.glb or .obj):");
    ImGui::SetNextItemWidth(-1);
    if (ImGui::IsWindowAppearing()) ImGui::SetKeyboardFocusHere();
    bool go = ImGui::InputText("##path", &filePath, ImGuiInputTextFlags_EnterReturnsTrue);
    if (fileAction == FileAction::Import) {
      ImGui::PushItemWidth(260);
      editVec3("position (m)", importPosition, 0.01f);
      ImGui::DragFloat("scale", &importScale, 0.01f, 1e-4f, 1e4f, "%.3f", ImGuiSliderFlags_AlwaysClamp);
      ImGui::PopItemWidth();
    }
    go |= ImGui::Button("OK", ImVec2(100, 0));
    ImGui::SameLine();
    bool cancel = ImGui::Button("Cancel", ImVec2(100, 0));
    if (go) {
      try {
        if (fileAction == FileAction::Open) openFile(filePath);
        else if (fileAction == FileAction::Save) saveFile(filePath);
        else if (fileAction == FileAction::Import) importMesh(filePath);
        else exportFile(filePath);
        cancel = true;
      } catch (const Error& e) {
        status = e.what();
        statusIsError = true;
      }
    }
    if (statusIsError) ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "%s", status.c_str());
    if (cancel) {
      fileAction = FileAction::None;
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
}

// The autosave of a session that did not exit cleanly (autosave.h): restore it or discard it.
void Studio::Impl::drawRestorePrompt() {
  if (!restorePending) return;
  const char* title = "Restore session";
  if (!ImGui::IsPopupOpen(title)) ImGui::OpenPopup(title);
  ImGui::SetNextWindowSize(ImVec2(520, 0));
  if (!ImGui::BeginPopupModal(title, nullptr, ImGuiWindowFlags_NoSavedSettings)) return;
  ImGui::Text("Restore the session from %s?", autosave->leftoverTime().c_str());
  ImGui::TextWrapped("The studio did not exit cleanly; this is its autosave (%s).", autosave->path().c_str());
  const bool restore = ImGui::Button("Restore", ImVec2(100, 0));
  ImGui::SameLine();
  const bool discard = ImGui::Button("Discard", ImVec2(100, 0));
  if (restore || discard) {
    restorePending = false;
    ImGui::CloseCurrentPopup();
  }
  ImGui::EndPopup();
  if (restore) restoreAutosave();
  else if (discard) discardAutosave();
}

void Studio::Impl::drawTools() {
  ImGui::TextDisabled("Tools (keys 1-9, 0)");
  const Tool tools[] = {Tool::View, Tool::Seed, Tool::BranchSeed, Tool::Cut, Tool::Drag,
                        Tool::PaintAttract, Tool::PaintRepel, Tool::MoveObstacle, Tool::Light, Tool::WindEmitter};
  const float half = (ImGui::GetContentRegionAvail().x - ImGui::GetStyle().ItemSpacing.x) * 0.5f;
  for (int i = 0; i < 10; ++i) {
    if (i % 2) ImGui::SameLine();
    std::string label = fmt::format("{} {}", (i + 1) % 10, toolName(tools[i]));
    if (ImGui::Selectable(label.c_str(), tool == tools[i], 0, ImVec2(half, 0))) tool = tools[i];
  }
}

void Studio::Impl::drawToolOptions() {
  ImGui::PushItemWidth(150);
  switch (tool) {
    case Tool::View:
      ImGui::TextWrapped("Left or right drag: orbit. Shift+drag or middle drag: pan. Wheel: zoom. "
                         "Double click: select.");
      break;
    case Tool::Seed:
      ImGui::Combo("model", &seedModel, kSeedModels, IM_ARRAYSIZE(kSeedModels));
      ImGui::InputTextWithHint("species", "model default", &seedSpecies);
      ImGui::TextWrapped("Click a surface to seed a plant there.");
      break;
    case Tool::BranchSeed: ImGui::TextWrapped("Click a grown branch of a particle plant to seed a branch."); break;
    case Tool::Cut: ImGui::TextWrapped("Click a branch to cut it; the piece beyond falls."); break;
    case Tool::Drag:
      ImGui::SliderFloat("strength", &dragStrength, 0.05f, 1.0f);
      ImGui::TextWrapped("Drag a particle plant's branch; colours show the strain.");
      break;
    case Tool::PaintAttract:
    case Tool::PaintRepel:
      ImGui::SliderFloat("radius (m)", &paintRadius, 0.02f, 1.0f);
      ImGui::SliderFloat("strength", &paintStrength, 0.0f, 5.0f);
      ImGui::TextWrapped("Drag over surfaces to paint.");
      break;
    case Tool::MoveObstacle:
      ImGui::TextWrapped("Drag an obstacle to move it across the view; Shift+drag turns it about the vertical; "
                         "Ctrl+drag up or down scales it. The obstacle panel has exact fields.");
      break;
    case Tool::Light:
      ImGui::TextWrapped("Drag to turn the selected (or first) light; point lights move across the view.");
      break;
    case Tool::WindEmitter:
      ImGui::SliderFloat("speed (m/s)", &emitterSpeed, 0.5f, 20.0f);
      ImGui::SliderFloat("radius (m)", &emitterRadius, 0.05f, 2.0f);
      ImGui::TextWrapped("Click a surface: an emitter 1 m in front of it blows at it.");
      break;
  }
  ImGui::PopItemWidth();
}

void Studio::Impl::drawSceneTree() {
  const env::Environment& env = session->environment();
  ImGui::TextDisabled("Scene");
  auto item = [&](Selection::Kind kind, uint32_t index, const std::string& label) {
    if (ImGui::Selectable(label.c_str(), selection.is(kind, index))) selection = {kind, index, std::nullopt};
  };
  ImGui::SetNextItemOpen(true, ImGuiCond_Once);
  if (ImGui::TreeNode("Obstacles")) {
    for (uint32_t id = 0; id < env.obstacleCount(); ++id) {
      const env::ObstacleInfo& info = env.obstacle(id);
      item(Selection::Kind::Obstacle, id,
           fmt::format("{} ({})##o{}", info.name.empty() ? "obstacle" : info.name, env::obstacleKindName(info.kind), id));
    }
    ImGui::TreePop();
  }
  ImGui::SetNextItemOpen(true, ImGuiCond_Once);
  if (ImGui::TreeNode("Plants")) {
    const auto& plants = view.plants();
    for (uint32_t p = 0; p < std::min(plants.size(), session->plantCount()); ++p) {
      // A plant that stopped early or stays small is marked (its inspector says why).
      const bool problem = std::any_of(growthProblems.begin(), growthProblems.end(),
                                       [&](const session::Session::GrowthReport& r) { return r.plant == p; });
      item(Selection::Kind::Plant, p,
           fmt::format("{} [{}] {} seg{}##p{}", plants[p].name, session->plantSpec(p).model, plants[p].nodeCount(),
                       problem ? "  (!)" : "", p));
    }
    ImGui::TreePop();
  }
  ImGui::SetNextItemOpen(true, ImGuiCond_Once);
  if (ImGui::TreeNode("Lights")) {
    for (uint32_t i = 0; i < env.lights().size(); ++i)
      item(Selection::Kind::Light, i,
           fmt::format("{} light {}##l{}", env.lights()[i].type == env::Light::Type::Directional ? "directional" : "point",
                       i, i));
    ImGui::TreePop();
  }
  ImGui::SetNextItemOpen(true, ImGuiCond_Once);
  if (ImGui::TreeNode("Wind emitters")) {
    const auto& emitters = env.windField().settings().emitters;
    for (uint32_t i = 0; i < emitters.size(); ++i)
      item(Selection::Kind::Emitter, i, fmt::format("emitter {} ({:.1f} m/s)##e{}", i, emitters[i].speed, i));
    ImGui::TreePop();
  }
  ImGui::SetNextItemOpen(true, ImGuiCond_Once);
  if (ImGui::TreeNode("Strokes")) {
    for (uint32_t i = 0; i < env.strokes().size(); ++i) {
      const env::Stroke& s = env.strokes()[i];
      item(Selection::Kind::Stroke, i, fmt::format("{} ({} points)##s{}", s.attract ? "attract" : "repel",
                                                   s.points.size(), i));
    }
    ImGui::TreePop();
  }
}

void Studio::Impl::drawInspector() {
  switch (selection.kind) {
    case Selection::Kind::None:
      ImGui::TextWrapped("Select a plant, obstacle, light, emitter or stroke in the scene tree, or double click "
                         "in the viewport.");
      break;
    case Selection::Kind::Plant: drawPlantPanel(selection.index); break;
    case Selection::Kind::Obstacle: drawObstaclePanel(selection.index); break;
    case Selection::Kind::Light: drawLightPanel(selection.index); break;
    case Selection::Kind::Emitter: drawEmitterPanel(selection.index); break;
    case Selection::Kind::Stroke: drawStrokePanel(selection.index); break;
  }
}

void Studio::Impl::drawPlantPanel(uint32_t p) {
  const auto& plants = view.plants();
  if (p >= plants.size() || p >= session->plantCount()) {
    ImGui::TextDisabled("(not in the scene now)");
    return;
  }
  const plant::PlantModel& m = plants[p];
  const models::PlantSpec& spec = session->plantSpec(p);
  ImGui::Text("%s  (model %s)", m.name.c_str(), spec.model.c_str());
  ImGui::Text("%zu segments, %zu leaves", m.nodeCount(), m.leafCount());
  for (const session::Session::GrowthReport& r : growthProblems)
    if (r.plant == p) {
      ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.8f, 0.3f, 1));
      ImGui::TextWrapped("%s: %s", r.problem.stopped ? "stopped" : "stays small", r.problem.why.c_str());
      ImGui::PopStyleColor();
    }
  if (selection.node && *selection.node < m.nodeCount()) {
    uint32_t n = *selection.node;
    ImGui::Text("segment %u: length %.3f m, radius %.4f m, age %.1f s", n, m.length[n], m.radius[n], m.age[n]);
  }
  ImGui::Separator();
  if (const models::LiveSettings* live = std::as_const(session->system(p)).liveSettings()) {
    drawLiveSettings(p, *live);
    return;
  }
  if (spec.model == "lsystem") {
    if (const auto* params = spec.paramsAs<lsystem::LSystemParams>()) {
      const Json& d = session->plantDescription(p);
      std::string key = d.dump();
      if (!lsystemPanel.isOpenFor(p, key)) {
        // An edited grammar's text is in the plant's scene-file object; else it is the file's.
        std::string text = d.is_object() && d.contains("grammar_text") && d["grammar_text"].is_string()
                               ? d["grammar_text"].get<std::string>()
                               : lsystem::grammarSourceText(params->grammar->source).value_or(std::string());
        lsystemPanel.open(p, params->grammar, std::move(text), params->derivationLength, spec.position, session.get(),
                          std::move(key));
      }
      if (ImGui::CollapsingHeader("L-system editor", ImGuiTreeNodeFlags_DefaultOpen)) {
        if (std::optional<session::SetGrammar> edit = lsystemPanel.draw()) {
          if (!apply(*edit)) lsystemPanel.applyFailed(status);  // else it reopens on the new grammar
        }
      }
    }
  }
  if (spec.model == "graph") {
    if (const auto* params = spec.paramsAs<graph::GraphPlantParams>(); params && params->graph) {
      const Json& d = session->plantDescription(p);
      std::string key = d.dump();
      if (!graphPanel.isOpenFor(p, key)) {
        // An edited graph is in the plant's scene-file object; else it is the file's.
        Json document;
        if (d.is_object() && d.contains("graph_document")) document = d["graph_document"];
        else {
          try {
            document = readJsonFile(params->graph->source);
          } catch (const Error& e) {
            status = e.what();
            statusIsError = true;
          }
        }
        graphPanel.open(p, std::move(document), params->graph->source, std::move(key));
      }
      if (ImGui::CollapsingHeader("p-graph editor", ImGuiTreeNodeFlags_DefaultOpen)) {
        if (d.is_object() && d.contains("overrides"))
          ImGui::TextDisabled("the plant's \"overrides\" still replace what they name");
        if (std::optional<session::SetGraph> edit = graphPanel.draw())
          if (!apply(*edit)) graphPanel.applyFailed(status);  // else it reopens on the new graph
      }
    }
  }
  // The plant's scene-file object as it is now (edits above rewrite it).
  if (ImGui::CollapsingHeader("Plant settings (read-only)")) {
    const Json& description = session->plantDescription(p);
    std::string text = description.is_null() ? std::string("(added from code)") : description.dump(2);
    ImGui::BeginChild("settings", ImVec2(0, 260), true, ImGuiWindowFlags_HorizontalScrollbar);
    ImGui::TextUnformatted(text.c_str());
    ImGui::EndChild();
  }
}

// A model's live settings (models::LiveSettings), applied through SetSpecies edits when a
// field is released.
void Studio::Impl::drawLiveSettings(uint32_t p, const models::LiveSettings& settings) {
  const size_t inSystem = session->indexInSystem(p);
  ImGui::Text("%s", settings.settingsTitle(inSystem).c_str());
  ImGui::TextDisabled("N = %zu plant(s) in the scene", session->plantCount());
  ImGui::PushItemWidth(150);
  std::string group;
  for (const models::LiveSettings::Setting& f : settings.liveSettings(inSystem)) {
    if (f.group != group) {
      if (!group.empty()) ImGui::Separator();
      group = f.group;
    }
    bool released = false;
    double value = f.value;
    if (f.integer) {
      int v = int(f.value);
      ImGui::SliderInt(f.label.c_str(), &v, int(f.min), int(f.max));
      released = ImGui::IsItemDeactivatedAfterEdit() && v != int(f.value);
      value = v;
    } else {
      float v = float(f.value);
      const std::string format = fmt::format("%.{}f", f.decimals);
      ImGui::SliderFloat(f.label.c_str(), &v, float(f.min), float(f.max), format.c_str());
      released = ImGui::IsItemDeactivatedAfterEdit() && v != float(f.value);
      value = v;
    }
    if (released) {
      session::SetSpecies edit;
      edit.plant = p;
      edit.keys = f.integer ? Json::object({{f.key, int64_t(value)}}) : Json::object({{f.key, float(value)}});
      apply(edit);
    }
  }
  ImGui::PopItemWidth();
}

void Studio::Impl::drawObstaclePanel(uint32_t id) {
  const env::Environment& env = session->environment();
  if (id >= env.obstacleCount()) {
    ImGui::TextDisabled("(not in the scene now)");
    return;
  }
  const env::ObstacleInfo& info = env.obstacle(id);
  ImGui::Text("Obstacle %s (%s)", info.name.c_str(), env::obstacleKindName(info.kind));
  ImGui::Text("%zu triangles%s", info.triangles, info.closed ? ", closed" : "");
  if (const std::string& path = session->obstaclePath(id); !path.empty()) ImGui::TextWrapped("imported from %s", path.c_str());
  Vec3 position = info.worldFromLocal.translation;
  Vec3 rotation = degreesFromQuat(info.worldFromLocal.rotation);
  Vec3 scale = session->obstacleScale(id);
  ImGui::PushItemWidth(220);
  bool moved = editVec3("position (m)", position, 0.01f);
  bool turned = editVec3("rotation (deg)", rotation, 0.5f, "%.1f");
  bool scaled = editVec3("scale", scale, 0.005f);
  float uniform = std::cbrt(scale.x() * scale.y() * scale.z());
  ImGui::DragFloat("uniform scale", &uniform, 0.005f, 1e-4f, 1e4f, "%.3f", ImGuiSliderFlags_AlwaysClamp);
  if (ImGui::IsItemDeactivatedAfterEdit()) {
    // Keeps the proportions of a non-uniform scale.
    const float now = std::cbrt(session->obstacleScale(id).prod());
    scale = session->obstacleScale(id) * (uniform / std::max(now, 1e-6f));
    scaled = true;
  }
  ImGui::PopItemWidth();
  ImGui::TextDisabled("scale: the mesh in its own frame, 1 = as read");
  if (moved || turned || scaled) {
    RigidTransform t = info.worldFromLocal;
    t.translation = position;
    if (turned) t.rotation = quatFromEulerDegrees(rotation);
    std::optional<Vec3> newScale;
    if (scaled) newScale = scale.cwiseMax(Vec3::Constant(1e-4f)).cwiseMin(Vec3::Constant(1e4f));
    apply(session::MoveObstacle{id, t, newScale});
  }
}

void Studio::Impl::drawLightPanel(uint32_t index) {
  const auto& lights = session->environment().lights();
  if (index >= lights.size()) {
    ImGui::TextDisabled("(not in the scene now)");
    return;
  }
  env::Light l = gesture.active && gesture.tool == Tool::Light ? gesture.lightPreview : lights[index];
  ImGui::Text("%s light %u", l.type == env::Light::Type::Directional ? "Directional" : "Point", index);
  ImGui::PushItemWidth(220);
  bool changed = false;
  const auto& schema = scene::lightSchema();
  if (l.type == env::Light::Type::Directional) {
    changed |= editVec3(fieldLabel(schema, "direction").c_str(), l.direction, 0.01f);
    if (l.direction.squaredNorm() > 1e-8f) l.direction.normalize();
    else l.direction = lights[index].direction;
  } else {
    changed |= editVec3(fieldLabel(schema, "position").c_str(), l.position, 0.01f);
  }
  changed |= fieldSlider(schema.at("intensity"), l);
  ImGui::PopItemWidth();
  if (changed) apply(session::MoveLight{index, l});
}

void Studio::Impl::drawEmitterPanel(uint32_t index) {
  const auto& emitters = session->environment().windField().settings().emitters;
  if (index >= emitters.size()) {
    ImGui::TextDisabled("(not in the scene now)");
    return;
  }
  env::WindEmitter e = emitters[index];
  ImGui::Text("Wind emitter %u", index);
  ImGui::PushItemWidth(220);
  const auto& schema = scene::emitterSchema();
  bool changed = editVec3(fieldLabel(schema, "position").c_str(), e.position, 0.01f);
  changed |= editVec3(fieldLabel(schema, "direction").c_str(), e.direction, 0.01f);
  if (e.direction.squaredNorm() > 1e-8f) e.direction.normalize();
  else e.direction = emitters[index].direction;
  for (const char* key : {"speed", "radius", "reach", "spread"}) changed |= fieldSlider(schema.at(key), e);
  ImGui::PopItemWidth();
  if (changed) apply(session::EditEmitter{index, e});
  if (ImGui::Button("Remove emitter")) {
    if (apply(session::RemoveEmitter{index})) selection = {};
  }
}

void Studio::Impl::drawStrokePanel(uint32_t index) {
  const auto& strokes = session->environment().strokes();
  if (index >= strokes.size()) {
    ImGui::TextDisabled("(not in the scene now)");
    return;
  }
  const env::Stroke& s = strokes[index];
  ImGui::Text("%s stroke %u", s.attract ? "Attracting" : "Repelling", index);
  ImGui::Text("%zu points, radius %.3f m, strength %.2f", s.points.size(), s.radius, s.strength);
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  ImGui::TextWrapped("Strokes are painted with the paint tools and removed with undo.");
  ImGui::PopStyleColor();
}

void Studio::Impl::drawWindPanel() {
  if (!ImGui::CollapsingHeader("Wind", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const env::WindSettings& w = session->environment().windField().settings();
  // The scene's wind settings as their description names them (scene/settings_schema.h).
  const auto& schema = scene::windSchema();
  const auto& modes = schema.at("mode").choices;
  const size_t mode = std::min(size_t(w.mode), modes.size() - 1);
  ImGui::Text("%s %s, %s %.2f, %.2f, %.2f", std::string(schema.at("mode").label).c_str(),
              std::string(modes[mode]).c_str(), fieldLabel(schema, "velocity").c_str(), w.velocity.x(), w.velocity.y(),
              w.velocity.z());
  ImGui::Text("%zu emitter(s)", w.emitters.size());
  ImGui::Checkbox("sway in the wind", &sway);
  ImGui::SameLine();
  ImGui::TextDisabled("(branches and leaves move while the plants grow)");
  for (const char* key : {"gust_strength", "gust_period", "gust_scale", "gust_turn"}) {
    const auto& f = schema.at(key);
    ImGui::Text("%s: %.2f", f.labelWithUnit().c_str(), schema::fileValue(f, w));
  }
  if (const wind::SphAir* air = session->air()) {
    ImGui::Text("simulated air: %zu particles", air->count());
    ImGui::Checkbox("show the air", &showAir);
    ImGui::SameLine();
    ImGui::TextDisabled("(streaks: blue still, green the scene's wind, red twice it)");
  }
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  ImGui::TextWrapped("Emitters are added with the wind emitter tool and edited in their panel; the prevailing "
                     "wind comes from the scene file.");
  ImGui::PopStyleColor();
}

void Studio::Impl::drawTimeline() {
  if (ImGui::Button(playing ? "Pause" : "Play", ImVec2(70, 0))) playing = !playing;
  ImGui::SameLine();
  if (ImGui::Button("Step", ImVec2(60, 0))) stepOnce();
  ImGui::SameLine();
  ImGui::SetNextItemWidth(160);
  ImGui::SliderInt("steps / frame", &speed, 1, 20);
  ImGui::SameLine();
  ImGui::Text("step %u", session->stepCount());
  ImGui::SameLine(0, 30);
  ImGui::BeginDisabled(!editor->canUndo() || editor->dragging());
  if (ImGui::Button(fmt::format("Undo ({})", editor->undoDepth()).c_str())) undo();
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(!editor->canRedo() || editor->dragging());
  if (ImGui::Button(fmt::format("Redo ({})", editor->redoDepth()).c_str())) redo();
  ImGui::EndDisabled();
  if (script) {
    ImGui::SameLine(0, 30);
    ImGui::Text("script %zu/%zu edits", nextScriptEdit, script->edits.size());
  }
}

void Studio::Impl::drawStatus() {
  ImGui::Text("%zu plants  |  %zu segments  |  step %.1f ms  |  frame %.1f ms (sim %.1f, update %.1f, draw %.1f)  "
              "|  %s  |",
              session->plantCount(), session->segmentCount(), lastStepMs, timing.frame,
              timing.simulation, timing.update, timing.draw, toolName(tool));
  // Plants that stopped early or stay small, before the last action's status (a long line is
  // cut at the window's edge): the first one's cause, every one's whole message on hover.
  if (!growthProblems.empty()) {
    ImGui::SameLine();
    const std::string more =
        growthProblems.size() > 1 ? fmt::format("  (+{} more plants)", growthProblems.size() - 1) : std::string();
    const session::Session::GrowthReport& first = growthProblems.front();
    ImGui::TextColored(ImVec4(1, 0.8f, 0.3f, 1), "plant \"%s\" %s: %s%s  |",
                       session->plantSpec(first.plant).name.c_str(), first.problem.stopped ? "stopped" : "stays small",
                       first.problem.why.c_str(), more.c_str());
    if (ImGui::IsItemHovered()) {
      ImGui::BeginTooltip();
      for (const session::Session::GrowthReport& r : growthProblems) ImGui::TextUnformatted(r.problem.message.c_str());
      ImGui::EndTooltip();
    }
  }
  ImGui::SameLine();
  if (statusIsError) ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "%s", status.c_str());
  else ImGui::TextUnformatted(status.c_str());
}

}  // namespace tendril::studio
