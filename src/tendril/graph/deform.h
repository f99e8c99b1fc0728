// Free-form deformations of seed 004 ("Free-form deformations"; sidebar, FFD and Hyperpatch):
// the FFD component moves points by functions of their local coordinates, the Hyperpatch by a
// 3D Bézier lattice of degree 1 to 4 whose control points the user displaces.
//
// Both work in the frame of their instance: a world point is taken into it (without the
// instance's scale), moved, and taken back.
#pragma once

#include "tendril/graph/expand.h"

namespace tendril::graph {

// Deformer `d` of the tree applied to a world point. FFD functions that fail to evaluate are
// Errors naming their parameter.
Vec3 deformPoint(const ITree& tree, int32_t d, const Vec3& world);

// The Hyperpatch displacement at a local point: Σ B_i(u) B_j(v) B_k(w) offset_ijk with Bernstein
// polynomials of the lattice degree and (u, v, w) the point's position in the lattice box,
// clamped to [0, 1] (outside the box the boundary displacement continues). An undisplaced
// lattice is the identity (linear precision of Bézier volumes).
Vec3 hyperpatchOffset(const Deformer& d, const Vec3& local);

// The deformers of chain `chain` that move anything, innermost first.
std::vector<int32_t> chainDeformers(const ITree& tree, int32_t chain);

}  // namespace tendril::graph
