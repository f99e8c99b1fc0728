// The plant graph as JSON (`tendril grow --format skeleton` → <stem>.skeleton.json), for research
// tools that read plant architecture rather than meshes (an MTG importer such as OpenAlea's):
// per plant its nodes (internodes: parent, edge type, position, orientation, length, radius,
// age, branch order, flags by name), leaves and primitives, each record with an explicit
// "kind". The layout, key by key, is docs/skeleton-format.md ("format": "tendril-skeleton",
// "version": 1).
//
// Node ids are the PlantModel's node indices, the ids the .glb's _NODE_ID attribute carries.
// Numbers are 32-bit floats written in the shortest form that reads back to the same float, one
// record per line; the bytes depend only on the plants (not on the thread count). The file is
// replaced atomically (atomic_file.h).
#pragma once

#include "tendril/plant/plant_model.h"

#include <filesystem>
#include <string>
#include <vector>

namespace tendril::io {

inline constexpr const char* kSkeletonFormat = "tendril-skeleton";
inline constexpr int kSkeletonVersion = 1;

// Checks every plant (plant::validate; an Error names the plant) and writes them, in order.
void writeSkeleton(const std::vector<plant::PlantModel>& plants, const std::filesystem::path& path);

// The names the file gives the node flags (plant::NodeFlags), bit i named kNodeFlagNames[i].
inline constexpr const char* kNodeFlagNames[] = {"climbing", "branch_start", "apex",     "dead",
                                                 "anchored", "broken",       "leaf_node"};

}  // namespace tendril::io
