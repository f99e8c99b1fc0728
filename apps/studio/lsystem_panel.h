// The L-system editor panel: the grammar of the selected L-system plant as editable text,
// compiled on every change with the parser's diagnostics shown inline (line excerpt and caret),
// and a live re-derivation drawn in the viewport beside the plant as a preview.
#pragma once

#include "tendril/lsystem/lsystem.h"
#include "tendril/plant/plant_model.h"

#include <memory>
#include <optional>
#include <string>

namespace tendril::studio {

class LSystemPanel {
 public:
  // Shows `grammar` (the plant's) for the plant with index `plant` standing at `position`;
  // the preview's query modules are answered by `env` (which must outlive the panel's use).
  void open(uint32_t plant, const std::shared_ptr<const lsystem::Grammar>& grammar,
            std::optional<int> derivationLength, const Vec3& position, const env::Environment* env);
  bool isOpenFor(uint32_t plant) const { return plant_ == plant && open_; }
  void close() { open_ = false; preview_.reset(); }
  // The ImGui contents (inside an open window).
  void draw();
  // The latest derivation of the edited text (nothing while the text has errors).
  const plant::PlantModel* preview() const { return preview_ ? &*preview_ : nullptr; }

 private:
  void rebuild();

  bool open_ = false;
  uint32_t plant_ = 0;
  std::string source_;
  std::string text_;
  std::optional<int> derivationLength_;
  int steps_ = 0;
  Vec3 position_ = Vec3::Zero();
  const env::Environment* env_ = nullptr;
  std::string error_;       // one-line message
  std::string diagnostic_;  // excerpt with a caret
  std::optional<plant::PlantModel> preview_;
  size_t modules_ = 0;
  double deriveMs_ = 0.0;
};

}  // namespace tendril::studio
