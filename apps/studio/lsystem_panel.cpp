#include "lsystem_panel.h"

#include "tendril/core/error.h"
#include "tendril/core/timer.h"
#include "tendril/env/seed_check.h"
#include "tendril/lsystem/lsystem_model.h"
#include "tendril/session/grow_alone.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>

namespace tendril::studio {

namespace {
// A preview derivation stops growing past this many modules so typing stays responsive.
constexpr size_t kPreviewModuleLimit = 200000;
}  // namespace

void LSystemPanel::open(uint32_t plant, const std::shared_ptr<const lsystem::Grammar>& grammar, std::string text,
                        std::optional<int> derivationLength, const Vec3& position, const session::Session* session,
                        std::string description) {
  open_ = true;
  description_ = std::move(description);
  plant_ = plant;
  source_ = grammar->source;
  text_ = plantText_ = std::move(text);
  derivationLength_ = derivationLength;
  steps_ = plantSteps_ = derivationLength.value_or(grammar->derivationLength);
  position_ = position;
  session_ = session;
  rebuild();
}

void LSystemPanel::rebuild() {
  error_.clear();
  diagnostic_.clear();
  preview_.reset();
  modules_ = 0;
  try {
    lsystem::CompileOptions options;
    options.dir = std::filesystem::path(source_).parent_path();
    auto grammar = lsystem::compileGrammar(text_, "editor", options);
    // The plant with the edited grammar, as the scene would grow it on its own (its seed, the
    // scene's seed; session/grow_alone.h), beside the plant so that the two can be compared:
    // at the first of a few places around it where it may start.
    models::PlantSpec plant;
    plant.name = "preview";
    if (plant_ < session_->plantCount()) {
      plant.direction = session_->plantSpec(plant_).direction;
      plant.seed = session_->plantSpec(plant_).seed;
    }
    const env::Environment& env = session_->environment();
    plant.position = position_ + Vec3(0.6f, 0.0f, 0.0f);
    for (const Vec3& offset : {Vec3(-0.6f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.6f), Vec3(0.0f, 0.0f, -0.6f)}) {
      if (!env::seedInsideObstacle(env, plant.position, plant.direction)) break;
      plant.position = position_ + offset;
    }
    Timer timer;
    auto modules = [](const models::PlantSystem& s) { return lsystem::derivationOf(s, 0)->string().size(); };
    std::unique_ptr<models::PlantSystem> system =
        session::growAlone(*session_, lsystem::lsystemPlant(std::move(plant), grammar, steps_), uint32_t(std::max(steps_, 0)),
                           [&](const models::PlantSystem& s) { return modules(s) < kPreviewModuleLimit; });
    preview_ = system->snapshot(0);
    modules_ = modules(*system);
    deriveMs_ = timer.milliseconds();
  } catch (const Error& e) {
    error_ = e.what();
    diagnostic_ = lsystem::renderDiagnostic(text_, e);
  }
}

void LSystemPanel::applyFailed(const std::string& message) {
  error_ = message;
  diagnostic_.clear();
}

std::optional<session::SetGrammar> LSystemPanel::draw() {
  if (!open_) return std::nullopt;
  ImGui::TextDisabled("%s", source_.c_str());
  bool changed = ImGui::InputTextMultiline("##grammar", &text_, ImVec2(-1, ImGui::GetTextLineHeight() * 16),
                                           ImGuiInputTextFlags_AllowTabInput);
  ImGui::SetNextItemWidth(120);
  changed |= ImGui::DragInt("derivation steps", &steps_, 0.2f, 0, 100000);
  if (changed) rebuild();
  std::optional<session::SetGrammar> edit;
  const bool edited = text_ != plantText_ || steps_ != plantSteps_;
  ImGui::BeginDisabled(!edited || !preview_);
  if (ImGui::Button("Apply to plant")) {
    edit = session::SetGrammar{plant_, text_, std::nullopt};
    if (steps_ != plantSteps_) edit->derivationLength = steps_;
  }
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(!edited);
  if (ImGui::Button("Revert")) {
    text_ = plantText_;
    steps_ = plantSteps_;
    rebuild();
  }
  ImGui::EndDisabled();
  if (edited) {
    ImGui::SameLine();
    ImGui::TextDisabled(preview_ ? "edited: apply re-derives the plant" : "fix the errors to apply");
  }
  if (!error_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1.0f));
    ImGui::TextWrapped("%s", error_.c_str());
    if (!diagnostic_.empty()) ImGui::TextUnformatted(diagnostic_.c_str());
    ImGui::PopStyleColor();
  } else if (preview_) {
    ImGui::Text("preview: %zu modules, %zu segments, %zu leaves (%.1f ms)", modules_, preview_->nodeCount(),
                preview_->leafCount(), deriveMs_);
    if (modules_ >= kPreviewModuleLimit) ImGui::TextDisabled("stopped at %zu modules", kPreviewModuleLimit);
  }
  return edit;
}

}  // namespace tendril::studio
