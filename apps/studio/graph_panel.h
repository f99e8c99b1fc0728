// The p-graph editor panel (seed 004): the selected graph plant's prototype graph as a tree under
// the root (camera) component, as in the paper's Fig. 3; the selected component's parameters,
// recursion depth and links edited in place; components added, linked, unlinked and deleted.
// Every change is a SetGraph edit the studio applies through the Editor (one undo entry each):
// the plant in the viewport is generated again at once, which is the live preview. A change the
// graph reader refuses (a cycle without a depth, a bad expression) shows its error and changes
// nothing.
#pragma once

#include "tendril/core/json_reader.h"
#include "tendril/session/edit.h"

#include <optional>
#include <string>

namespace tendril::studio {

class GraphPanel {
 public:
  // `document` is the plant's graph (its edited document, or its file's contents);
  // `description` the plant's scene-file object as text, so that the panel shows the plant's
  // graph again when it changes (an apply, an undo, a script). The selected component stays
  // selected when the same plant's graph changes.
  void open(uint32_t plant, Json document, std::string source, std::string description);
  bool isOpenFor(uint32_t plant, const std::string& description) const {
    return open_ && plant_ == plant && description_ == description;
  }
  void close() { open_ = false; }
  // The ImGui contents. Returns the edit of a change made this frame.
  std::optional<session::SetGraph> draw();
  // The edit draw() returned failed: its message is shown in the panel.
  void applyFailed(const std::string& message) { error_ = message; }
  const std::string& selected() const { return selected_; }

 private:
  void drawTree(const Json& link, std::vector<std::string>& path);
  void drawComponent(Json& doc, bool& changed);
  void drawAdd(Json& doc, bool& changed);

  bool open_ = false;
  uint32_t plant_ = 0;
  std::string source_;
  std::string description_;
  Json doc_;
  std::string selected_;  // component name ("" = none)
  std::string error_;
  // Inputs of the add / link / parameter fields.
  std::string newName_;
  int newType_ = 0;
  int linkTarget_ = 0;
  int linkType_ = 0;
  std::string paramKey_, paramValue_;
  std::string editingKey_, editingText_;  // a non-numeric parameter being typed
};

}  // namespace tendril::studio
