// The L-system editor panel: the grammar of the selected L-system plant as editable text,
// compiled on every change with the parser's diagnostics shown inline (line excerpt and caret),
// and a live re-derivation drawn in the viewport beside the plant as a preview: the plant with
// the edited grammar as the scene grows it (its seed, the scene's seed and environment). "Apply
// to plant" hands back a SetGrammar edit for the studio to apply through the Editor (undoable).
#pragma once

#include "tendril/lsystem/lsystem.h"
#include "tendril/plant/plant_model.h"
#include "tendril/session/edit.h"
#include "tendril/session/session.h"

#include <memory>
#include <optional>
#include <string>

namespace tendril::studio {

class LSystemPanel {
 public:
  // Shows `grammar` (the plant's) for the plant with index `plant` standing at `position`;
  // the preview's query modules are answered by the session's environment (the session must
  // outlive the panel's use; its environment is looked up at each derivation).
  // `text` is the grammar's text (the plant's edited text, or its file's); `description` the
  // plant's scene-file object as text, so that the panel shows the plant's grammar again when
  // it changes (an apply, an undo, a script).
  void open(uint32_t plant, const std::shared_ptr<const lsystem::Grammar>& grammar, std::string text,
            std::optional<int> derivationLength, const Vec3& position, const session::Session* session,
            std::string description);
  bool isOpenFor(uint32_t plant, const std::string& description) const {
    return open_ && plant_ == plant && description_ == description;
  }
  void close() { open_ = false; preview_.reset(); }
  // The ImGui contents (inside an open window). Returns the edit that applies the text (and
  // the derivation steps, when changed) to the plant when "Apply to plant" was pressed.
  std::optional<session::SetGrammar> draw();
  // An edit made by draw() failed: its message is shown under the text.
  void applyFailed(const std::string& message);
  // The latest derivation of the edited text (nothing while the text has errors).
  const plant::PlantModel* preview() const { return preview_ ? &*preview_ : nullptr; }

 private:
  void rebuild();

  bool open_ = false;
  uint32_t plant_ = 0;
  std::string source_;
  std::string text_;
  std::string plantText_;
  std::string description_;  // the plant's own grammar text, for "changed" and "Revert"
  std::optional<int> derivationLength_;
  int plantSteps_ = 0;     // the plant's derivation length
  int steps_ = 0;
  Vec3 position_ = Vec3::Zero();
  const session::Session* session_ = nullptr;
  std::string error_;       // one-line message
  std::string diagnostic_;  // excerpt with a caret
  std::optional<plant::PlantModel> preview_;
  size_t modules_ = 0;
  double deriveMs_ = 0.0;
};

}  // namespace tendril::studio
