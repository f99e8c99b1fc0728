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

}  // namespace tendril::particles
