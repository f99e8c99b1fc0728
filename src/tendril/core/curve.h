// Curves for generalised cylinders: centripetal Catmull-Rom splines through the skeleton's
// segment points and rotation-minimising frames along them.
//
// seed 003 §3.10 sweeps a cylindrical NURBS surface through the internode segments, one
// control vertex per segment with its radius. We interpolate instead of approximating (the
// surface passes through every segment point, so leaves stay on their branch):
//  * centripetal Catmull-Rom (alpha = 1/2) has no cusps or self-intersections within a segment
//    (Yuksel, Schaefer & Keyser 2011, "Parameterization and applications of Catmull-Rom
//    curves"), which uniform Catmull-Rom shows on the short-long segment runs growth produces;
//  * rotation-minimising frames by double reflection (Wang, Jüttler, Zheng & Liu 2008,
//    "Computation of rotation minimizing frames", ACM TOG 27(1)) keep the bark from twisting.
#pragma once

#include "tendril/core/math.h"

#include <span>

namespace tendril {

// One segment of a curve in cubic Hermite form: p(s) for s in [0, 1] runs from p1 to p2.
struct CurveSegment {
  Vec3 p1 = Vec3::Zero(), p2 = Vec3::Zero();
  Vec3 m1 = Vec3::Zero(), m2 = Vec3::Zero();  // tangents dp/ds at s = 0 and s = 1

  Vec3 point(float s) const;
  Vec3 derivative(float s) const;  // dp/ds
};

// The centripetal Catmull-Rom segment between p1 and p2, shaped by the neighbours p0 and p3.
// p1 and p2 should be distinct (callers merge coincident points first); the result is finite
// even when they are not. At a curve's ends pass the reflected neighbour, 2·p1 − p2 (or 2·p2 − p1).
CurveSegment centripetalCatmullRom(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3);

// Carries the unit normal r0 of the frame at (x0, t0) to the frame at (x1, t1) by two
// reflections (Wang et al. 2008, Algorithm 1): the first maps x0 to x1, the second maps the
// reflected tangent onto t1. t0, t1 unit tangents, r0 ⟂ t0 unit. Returns a unit normal ⟂ t1.
Vec3 doubleReflection(const Vec3& x0, const Vec3& t0, const Vec3& r0, const Vec3& x1, const Vec3& t1);

// Rotation-minimising normals along a polyline with unit tangents. normals[0] is r0 made
// perpendicular to tangents[0] (any perpendicular when r0 is parallel to it). All spans have
// the same length.
void rotationMinimizingFrames(std::span<const Vec3> points, std::span<const Vec3> tangents,
                              const Vec3& r0, std::span<Vec3> normals);

// The unit vector closest to `hint` that is perpendicular to unit `t` (Gram-Schmidt), or any
// perpendicular when hint is (nearly) parallel to t.
Vec3 perpendicularTo(const Vec3& t, const Vec3& hint);

}  // namespace tendril
