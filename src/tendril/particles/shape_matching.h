// Rotation extraction for shape matching.
#pragma once

#include "tendril/core/math.h"

namespace tendril::particles {

// The rotation part of A (A = R S), by Müller, Bender, Chentanez and Macklin 2016, "A robust
// method to extract the rotational part of deformations": starting from `q` (warm start: the
// last step's rotation), iterate R <- exp(Σ r_i × a_i / (|Σ r_i · a_i| + ε)) R over the columns
// r_i of R and a_i of A. Unlike a polar decomposition through A^T A it stays well defined for
// the rank-deficient moment matrices of collinear particle chains, and never flips to a
// reflection.
Quat extractRotation(const Mat3& A, Quat q, int maxIterations = 8);

// The shape-matching passes are compiled twice, for the baseline instruction set and for AVX2
// (the same SSE operations in three-operand form, without fused multiply-adds: the same bits),
// and the AVX2 ones run where the CPU has it. Whether they run now, and a switch that keeps to
// the baseline ones (process-wide, for tests).
bool avx2ShapeMatching();
void forceBaselineShapeMatching(bool on);

}  // namespace tendril::particles
