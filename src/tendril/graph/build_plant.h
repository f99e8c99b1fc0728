// Geometry from the i-tree (seed 004: "the system traverses the tree to produce the
// geometry"), as a PlantModel:
//  * tube stems (Tree, and Horns without a cross-section or primitive) are skeleton chains,
//    parents before children, kNodeBranchStart on branches, so mesh/, export, wind and the
//    studio treat them like any other plant;
//  * flat textured leaves are PlantModel leaves (textured cards; shape ids per distinct
//    texture, aspect and tint); curved or outlined leaves, Simple solids, Revo surfaces, Horn
//    sections and the strips between point sets are primitives attached to the node they hang
//    from, so moving that node moves them;
//  * FFD and Hyperpatch deformations are applied here (see build_plant.cpp for how geometry
//    switched off from a deformation rides along with the node it hangs from).
#pragma once

#include "tendril/graph/expand.h"
#include "tendril/plant/plant_model.h"

namespace tendril::graph {

// Throws Error for functions that fail while deforming, more than 65535 distinct leaf shapes,
// and (as an internal check) an invalid PlantModel.
plant::PlantModel buildPlant(const ITree& tree);

// expand + buildPlant.
plant::PlantModel generatePlant(std::shared_ptr<const Graph> graph, const ExpandOptions& options = {});

}  // namespace tendril::graph
