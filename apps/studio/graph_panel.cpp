#include "graph_panel.h"

#include "tendril/core/error.h"

#include <fmt/format.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>

namespace tendril::studio {
namespace {

constexpr const char* kTypes[] = {"simple", "revo",   "horn", "leaf",       "tree", "hydra",
                                  "wreath", "phiball", "ffd", "hyperpatch", "world"};
constexpr const char* kLinkTypes[] = {"child", "branch", "leaf"};

// A link is "name" (a child link) or {"to": "name", "type": ...}.
std::string linkTarget(const Json& link) {
  if (link.is_string()) return link.get<std::string>();
  if (link.is_object() && link.contains("to") && link["to"].is_string()) return link["to"].get<std::string>();
  return {};
}
std::string linkType(const Json& link) {
  if (link.is_object() && link.contains("type") && link["type"].is_string()) return link["type"].get<std::string>();
  return "child";
}

Json* components(Json& doc) {
  if (!doc.is_object() || !doc.contains("components") || !doc["components"].is_array()) return nullptr;
  return &doc["components"];
}
Json* component(Json& doc, const std::string& name) {
  Json* list = components(doc);
  if (!list) return nullptr;
  for (Json& c : *list)
    if (c.is_object() && c.contains("name") && c["name"] == name) return &c;
  return nullptr;
}

std::vector<std::string> componentNames(const Json& doc) {
  std::vector<std::string> names;
  if (doc.is_object() && doc.contains("components") && doc["components"].is_array())
    for (const Json& c : doc["components"])
      if (c.is_object() && c.contains("name") && c["name"].is_string()) names.push_back(c["name"].get<std::string>());
  return names;
}

// The links array of the root (name "") or of a component, made when missing.
Json* linksOf(Json& doc, const std::string& name) {
  Json* owner = name.empty() ? (doc.contains("root") && doc["root"].is_object() ? &doc["root"] : nullptr)
                             : component(doc, name);
  if (!owner) return nullptr;
  if (!owner->contains("links") || !(*owner)["links"].is_array()) (*owner)["links"] = Json::array();
  return &(*owner)["links"];
}

}  // namespace

void GraphPanel::open(uint32_t plant, Json document, std::string source, std::string description) {
  if (!open_ || plant_ != plant) {
    selected_.clear();
    error_.clear();
  }
  open_ = true;
  plant_ = plant;
  doc_ = std::move(document);
  source_ = std::move(source);
  description_ = std::move(description);
  if (!selected_.empty() && !component(doc_, selected_)) selected_.clear();
  editingKey_.clear();
}

void GraphPanel::drawTree(const Json& link, std::vector<std::string>& path) {
  const std::string name = linkTarget(link);
  const Json* c = component(doc_, name);
  if (!c) {
    ImGui::BulletText("%s (missing)", name.c_str());
    return;
  }
  const std::string type = c->contains("type") && (*c)["type"].is_string() ? (*c)["type"].get<std::string>() : "?";
  const int depth = c->contains("depth") && (*c)["depth"].is_number_integer() ? (*c)["depth"].get<int>() : 0;
  if (std::find(path.begin(), path.end(), name) != path.end()) {
    ImGui::BulletText("%s (%s link, back to it)", name.c_str(), linkType(link).c_str());
    return;
  }
  const bool leaf = !c->contains("links") || !(*c)["links"].is_array() || (*c)["links"].empty();
  ImGuiTreeNodeFlags flags = ImGuiTreeNodeFlags_DefaultOpen | ImGuiTreeNodeFlags_OpenOnArrow |
                             ImGuiTreeNodeFlags_SpanAvailWidth;
  if (leaf) flags |= ImGuiTreeNodeFlags_Leaf | ImGuiTreeNodeFlags_NoTreePushOnOpen;
  if (selected_ == name) flags |= ImGuiTreeNodeFlags_Selected;
  const std::string label = fmt::format("{} ({}, {} link){}##{}", name, type, linkType(link),
                                        depth > 0 ? fmt::format(" depth {}", depth) : std::string(),
                                        fmt::format("{}/{}", fmt::join(path, "/"), name));
  const bool opened = ImGui::TreeNodeEx(label.c_str(), flags);
  if (ImGui::IsItemClicked() && !ImGui::IsItemToggledOpen()) selected_ = name;
  if (!opened || leaf) return;
  path.push_back(name);
  for (const Json& l : (*c)["links"]) drawTree(l, path);
  path.pop_back();
  ImGui::TreePop();
}

void GraphPanel::drawComponent(Json& doc, bool& changed) {
  Json* c = component(doc, selected_);
  if (!c) return;
  ImGui::Separator();
  ImGui::Text("%s (%s)", selected_.c_str(), c->value("type", std::string("?")).c_str());
  ImGui::PushItemWidth(170);

  // Recursion depth (0 = not limited; needed on every cycle).
  int depth = c->contains("depth") && (*c)["depth"].is_number_integer() ? (*c)["depth"].get<int>() : 0;
  ImGui::DragInt("depth", &depth, 0.1f, 0, 64);
  if (ImGui::IsItemDeactivatedAfterEdit()) {
    if (depth > 0) (*c)["depth"] = depth;
    else c->erase("depth");
    changed = true;
  }

  // Parameters: numbers and short number lists as drag fields, anything else (expressions,
  // curves, strings) as JSON text applied with Enter.
  if (!c->contains("params") || !(*c)["params"].is_object()) (*c)["params"] = Json::object();
  Json& params = (*c)["params"];
  std::string removeKey;
  for (auto it = params.begin(); it != params.end(); ++it) {
    const std::string& key = it.key();
    Json& v = it.value();
    ImGui::PushID(key.c_str());
    if (ImGui::SmallButton("x")) removeKey = key;
    ImGui::SameLine();
    const bool numbers = v.is_array() && v.size() >= 2 && v.size() <= 4 &&
                         std::all_of(v.begin(), v.end(), [](const Json& e) { return e.is_number(); });
    if (v.is_number_integer()) {
      int x = v.get<int>();
      ImGui::DragInt(key.c_str(), &x, 0.2f);
      if (ImGui::IsItemDeactivatedAfterEdit()) v = x, changed = true;
    } else if (v.is_number()) {
      float x = v.get<float>();
      ImGui::DragFloat(key.c_str(), &x, std::max(0.001f, std::abs(x) * 0.01f), 0.0f, 0.0f, "%.4g");
      if (ImGui::IsItemDeactivatedAfterEdit()) v = x, changed = true;
    } else if (numbers) {
      float x[4] = {};
      for (size_t i = 0; i < v.size(); ++i) x[i] = v[i].get<float>();
      const float speed = std::max(0.001f, std::abs(x[0]) * 0.01f);
      if (v.size() == 2) ImGui::DragFloat2(key.c_str(), x, speed, 0.0f, 0.0f, "%.4g");
      else if (v.size() == 3) ImGui::DragFloat3(key.c_str(), x, speed, 0.0f, 0.0f, "%.4g");
      else ImGui::DragFloat4(key.c_str(), x, speed, 0.0f, 0.0f, "%.4g");
      if (ImGui::IsItemDeactivatedAfterEdit()) {
        for (size_t i = 0; i < v.size(); ++i) v[i] = x[i];
        changed = true;
      }
    } else {
      std::string text = editingKey_ == key ? editingText_ : v.dump();
      if (ImGui::InputText(key.c_str(), &text, ImGuiInputTextFlags_EnterReturnsTrue)) {
        // JSON when it reads as JSON, else a string (an expression or a texture name).
        try {
          v = parseJson(text, "parameter");
        } catch (const Error&) {
          v = text;
        }
        editingKey_.clear();
        changed = true;
      } else if (ImGui::IsItemActive()) {
        editingKey_ = key;
        editingText_ = text;
      } else if (editingKey_ == key) {
        editingKey_.clear();
      }
    }
    ImGui::PopID();
  }
  if (!removeKey.empty()) params.erase(removeKey), changed = true;
  ImGui::SetNextItemWidth(90);
  ImGui::InputTextWithHint("##pkey", "parameter", &paramKey_);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(110);
  ImGui::InputTextWithHint("##pvalue", "value (JSON)", &paramValue_);
  ImGui::SameLine();
  ImGui::BeginDisabled(paramKey_.empty() || paramValue_.empty());
  if (ImGui::Button("Set")) {
    try {
      params[paramKey_] = parseJson(paramValue_, "parameter");
    } catch (const Error&) {
      params[paramKey_] = paramValue_;
    }
    changed = true;
  }
  ImGui::EndDisabled();

  // Links of the component.
  ImGui::TextDisabled("links");
  Json* links = linksOf(doc, selected_);
  int removeLink = -1;
  for (size_t i = 0; links && i < links->size(); ++i) {
    ImGui::PushID(int(i));
    if (ImGui::SmallButton("x")) removeLink = int(i);
    ImGui::SameLine();
    ImGui::Text("%s -> %s", linkType((*links)[i]).c_str(), linkTarget((*links)[i]).c_str());
    ImGui::PopID();
  }
  if (removeLink >= 0) links->erase(size_t(removeLink)), changed = true;
  const std::vector<std::string> names = componentNames(doc);
  if (!names.empty()) {
    linkTarget_ = std::clamp(linkTarget_, 0, int(names.size()) - 1);
    ImGui::SetNextItemWidth(120);
    if (ImGui::BeginCombo("##target", names[size_t(linkTarget_)].c_str())) {
      for (int i = 0; i < int(names.size()); ++i)
        if (ImGui::Selectable(names[size_t(i)].c_str(), i == linkTarget_)) linkTarget_ = i;
      ImGui::EndCombo();
    }
    ImGui::SameLine();
    ImGui::SetNextItemWidth(70);
    ImGui::Combo("##linktype", &linkType_, kLinkTypes, IM_ARRAYSIZE(kLinkTypes));
    ImGui::SameLine();
    if (ImGui::Button("Link") && links) {
      const std::string& to = names[size_t(linkTarget_)];
      links->push_back(linkType_ == 0 ? Json(to) : Json{{"to", to}, {"type", kLinkTypes[linkType_]}});
      changed = true;
    }
  }
  ImGui::PopItemWidth();

  if (ImGui::Button("Delete component")) {
    // The component and every link to it go.
    Json* list = components(doc);
    for (size_t i = 0; list && i < list->size(); ++i)
      if ((*list)[i].value("name", std::string()) == selected_) {
        list->erase(i);
        break;
      }
    std::vector<std::string> owners = componentNames(doc);
    owners.push_back("");
    for (const std::string& owner : owners)
      if (Json* l = linksOf(doc, owner)) {
        Json kept = Json::array();
        for (const Json& link : *l)
          if (linkTarget(link) != selected_) kept.push_back(link);
        *l = std::move(kept);
      }
    changed = true;
  }
}

void GraphPanel::drawAdd(Json& doc, bool& changed) {
  ImGui::Separator();
  ImGui::TextDisabled("add a component under %s", selected_.empty() ? "the root" : selected_.c_str());
  ImGui::SetNextItemWidth(110);
  ImGui::InputTextWithHint("##newname", "name", &newName_);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(90);
  ImGui::Combo("##newtype", &newType_, kTypes, IM_ARRAYSIZE(kTypes));
  ImGui::SameLine();
  ImGui::BeginDisabled(newName_.empty());
  if (ImGui::Button("Add")) {
    Json* list = components(doc);
    Json* links = linksOf(doc, selected_);
    if (list && links) {
      list->push_back(Json{{"name", newName_}, {"type", kTypes[newType_]}, {"params", Json::object()}});
      links->push_back(newName_);
      selected_ = newName_;
      newName_.clear();
      changed = true;
    }
  }
  ImGui::EndDisabled();
}

std::optional<session::SetGraph> GraphPanel::draw() {
  if (!open_) return std::nullopt;
  ImGui::TextDisabled("%s: %zu components", source_.c_str(), componentNames(doc_).size());
  ImGui::BeginChild("pgraph", ImVec2(0, 190), true);
  const bool rootOpen = ImGui::TreeNodeEx("camera (root)", ImGuiTreeNodeFlags_DefaultOpen |
                                                               (selected_.empty() ? ImGuiTreeNodeFlags_Selected : 0));
  if (ImGui::IsItemClicked() && !ImGui::IsItemToggledOpen()) selected_.clear();
  if (rootOpen) {
    if (doc_.contains("root") && doc_["root"].is_object() && doc_["root"].contains("links") &&
        doc_["root"]["links"].is_array()) {
      std::vector<std::string> path;
      for (const Json& l : doc_["root"]["links"]) drawTree(l, path);
    }
    ImGui::TreePop();
  }
  ImGui::EndChild();

  Json doc = doc_;  // changes go to a copy: the plant's graph changes only through the edit
  bool changed = false;
  drawComponent(doc, changed);
  drawAdd(doc, changed);
  if (!error_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1.0f));
    ImGui::TextWrapped("%s", error_.c_str());
    ImGui::PopStyleColor();
  }
  if (!changed) return std::nullopt;
  error_.clear();
  return session::SetGraph{plant_, std::move(doc)};
}

}  // namespace tendril::studio
