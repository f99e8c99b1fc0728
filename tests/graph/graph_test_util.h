// Helpers for the graph tests: graphs from inline JSON, and small geometric measures.
#pragma once

#include "tendril/core/error.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/expand.h"
#include "tendril/graph/graph.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>

namespace tendril::graphtest {

inline std::shared_ptr<const graph::Graph> parse(const std::string& text,
                                                 const std::vector<graph::Override>& overrides = {}) {
  return graph::parseGraph(parseJson(text, "test.json"), "test.json", TENDRIL_SOURCE_DIR, overrides);
}

// The Error a graph text produces when read (and expanded and built, if reading succeeds).
inline Error errorOf(const std::string& text) {
  try {
    graph::generatePlant(parse(text));
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for " << text;
  return Error("", "", "");
}

// Instances of the named component.
inline std::vector<const graph::Instance*> instancesOf(const graph::ITree& t, const std::string& name) {
  std::vector<const graph::Instance*> out;
  int32_t c = t.graph->find(name);
  for (const graph::Instance& i : t.instances)
    if (i.component == c) out.push_back(&i);
  return out;
}

}  // namespace tendril::graphtest
