// The prototype graph (p-graph) of seed 004: components connected by child, branch and leaf
// links, read from a graph file (docs/graph-format.md).
//
// Reading is strict like scene files: unknown keys, wrong types and out-of-range values are
// Errors naming the file and the JSON pointer; links to missing components, duplicate names
// and cycles in which no component has a recursion depth are Errors naming the link. A Graph
// is immutable once read and may be expanded by several threads at once.
#pragma once

#include "tendril/core/json_reader.h"
#include "tendril/graph/components.h"
#include "tendril/plant/plant_model.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace tendril::graph {

inline constexpr int kGraphFormatVersion = 1;

// seed 004, Fig. 3: (a) child link, (b) branch link, (c) recursion, (d) leaf link.
enum class LinkType : uint8_t {
  Child,   // geometry placed relative to the parent's geometry (at its top / tip)
  Branch,  // multiplied as branches along the stem when the parent is a Tree, else a child link
  Leaf,    // when the parent is part of a recursion: created once, after the recursion ends
};
const char* linkTypeName(LinkType type);

struct Link {
  int32_t target = -1;  // component index
  LinkType type = LinkType::Child;
  uint32_t location = 0;  // ParamTable location of the link (for messages)
};

struct Component {
  std::string name;
  ComponentType type = ComponentType::Simple;
  std::vector<Link> links;
  int depth = 0;               // highest recursion depth; 0 = not limited (not allowed in a cycle)
  std::vector<int> exclude;    // flag list: iteration numbers not created (sorted)
  std::vector<int> only;       // flag list: if not empty, the only iteration numbers created
  BasicParams basic;
  ComponentParams params;
  // Derived: strongly connected component of the link graph, and whether it is a recursion
  // (a cycle through this component).
  int32_t scc = -1;
  bool recursive = false;
  uint32_t location = 0;       // pointer of the component object

  template <class T>
  const T& as() const { return std::get<T>(params); }
};

struct Camera {
  Vec3 eye = Vec3(3.0f, 2.0f, 4.0f);
  Vec3 target = Vec3(0.0f, 1.0f, 0.0f);
  float fov = 40.0f;  // degrees, vertical
  bool given = false;  // set in the file (else callers frame the model themselves)
};

struct GraphLight {
  Vec3 direction = Vec3(-0.3f, -1.0f, -0.4f).normalized();  // the way the light travels
  float intensity = 1.0f;
};

// seed 004: "Each p-graph has an additional root component, represented by a camera icon.
// Parameters of this component control the view and positions of light sources."
struct Graph {
  std::string name;
  std::string source;           // the file (for messages)
  std::filesystem::path baseDir;
  uint64_t seed = 1;
  size_t maxInstances = 4000000;  // capacity limit of the i-tree (raise "max_instances")
  Camera camera;
  std::vector<GraphLight> lights;
  plant::BarkMaterial bark;       // material of every tube stem (one per plant)
  std::vector<Link> rootLinks;
  std::vector<Component> components;
  ParamTable table;

  int32_t find(std::string_view name) const;
};

// Reads a graph file. `overrides` replace parameters ("component/parameter"); an override that
// names no component or parameter is an Error at the override's own location.
std::shared_ptr<const Graph> loadGraph(const std::filesystem::path& path, const std::vector<Override>& overrides = {});
std::shared_ptr<const Graph> parseGraph(const Json& json, const std::string& source,
                                        const std::filesystem::path& baseDir,
                                        const std::vector<Override>& overrides = {});

// "name=value" from a command line: the value is JSON when it parses as JSON, else a string
// (an expression). Errors name `source` ("command line") and `option` ("--set").
Override parseOverride(const std::string& text, const std::string& source, const std::string& option);

}  // namespace tendril::graph
