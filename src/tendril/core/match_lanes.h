// Shape-matching arithmetic for four particles at once, one per SSE lane (dynamics.cpp fits
// four particles of one breadth-first level side by side with it).
//
// Every operation below is the one Eigen 3.4 performs for the scalar fit, in the same order —
// sums of three terms as a + (b + c) (Eigen's unrolled reductions), four-term quaternion sums as
// (x + z) + (y + w) (its SSE reduction), quaternion products as its SSE kernel, A += M + d vᵀ as
// A + (M + d vᵀ) — and an IEEE operation on a lane gives the same bits as on a scalar, so a
// four-lane fit is bit for bit four scalar ones (tests/particles/match_lanes_test.cpp holds
// each function to its Eigen counterpart). The sine and cosine of the rotation extraction are
// taken per lane by the same library calls.
#pragma once

#include "tendril/core/math.h"

#include <emmintrin.h>

#include <cmath>

namespace tendril::lanes {

using F4 = float __attribute__((vector_size(16)));
using M4 = int __attribute__((vector_size(16)));

inline F4 sqrt4(F4 x) { return F4(_mm_sqrt_ps(__m128(x))); }
inline F4 abs4(F4 x) { return F4(_mm_andnot_ps(_mm_set1_ps(-0.0f), __m128(x))); }
inline F4 splat(float v) { return F4{v, v, v, v}; }

struct V3 {
  F4 x, y, z;
};
struct Q4 {  // Eigen's coefficient order
  F4 x, y, z, w;
};
struct M3 {
  F4 m[3][3];  // [row][column]
};

inline V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(F4 s, const V3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline V3 select(M4 m, const V3& a, const V3& b) { return {m ? a.x : b.x, m ? a.y : b.y, m ? a.z : b.z}; }
inline Q4 select(M4 m, const Q4& a, const Q4& b) {
  return {m ? a.x : b.x, m ? a.y : b.y, m ? a.z : b.z, m ? a.w : b.w};
}

inline V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline F4 dot(const V3& a, const V3& b) { return a.x * b.x + (a.y * b.y + a.z * b.z); }

// Eigen's quat_product for SSE.
inline Q4 operator*(const Q4& a, const Q4& b) {
  return {(a.x * b.w - a.z * b.y) + (a.y * b.z + a.w * b.x), (a.y * b.w - a.x * b.z) + (a.z * b.x + a.w * b.y),
          (a.z * b.w - a.y * b.x) + (a.x * b.y + a.w * b.z), (a.w * b.w - a.x * b.x) - (a.z * b.z + a.y * b.y)};
}
inline Q4 conjugate(const Q4& q) { return {-q.x, -q.y, -q.z, q.w}; }
inline Q4 negate(const Q4& q) { return {-q.x, -q.y, -q.z, -q.w}; }
inline F4 dot4(const Q4& a, const Q4& b) { return (a.x * b.x + a.z * b.z) + (a.y * b.y + a.w * b.w); }
// Quaternion::normalized(): unchanged where the squared norm is not positive.
inline Q4 normalized(const Q4& q) {
  const F4 z = dot4(q, q);
  const F4 n = sqrt4(z);
  return select(z > 0.0f, Q4{q.x / n, q.y / n, q.z / n, q.w / n}, q);
}
// Quaternion * Vector3 (Eigen's _transformVector).
inline V3 rotate(const Q4& q, const V3& v) {
  const V3 qv{q.x, q.y, q.z};
  V3 uv = cross(qv, v);
  uv = uv + uv;
  return (v + q.w * uv) + cross(qv, uv);
}
inline M3 toRotationMatrix(const Q4& q) {
  const F4 tx = 2.0f * q.x, ty = 2.0f * q.y, tz = 2.0f * q.z;
  const F4 twx = tx * q.w, twy = ty * q.w, twz = tz * q.w;
  const F4 txx = tx * q.x, txy = ty * q.x, txz = tz * q.x;
  const F4 tyy = ty * q.y, tyz = tz * q.y, tzz = tz * q.z;
  M3 r;
  r.m[0][0] = 1.0f - (tyy + tzz);
  r.m[0][1] = txy - twz;
  r.m[0][2] = txz + twy;
  r.m[1][0] = txy + twz;
  r.m[1][1] = 1.0f - (txx + tzz);
  r.m[1][2] = tyz - twx;
  r.m[2][0] = txz - twy;
  r.m[2][1] = tyz + twx;
  r.m[2][2] = 1.0f - (txx + tyy);
  return r;
}
inline M3 operator*(const M3& a, const M3& b) {
  M3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + (a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j]);
  return r;
}
// A += M + d vᵀ where `add` is set (A is kept where it is not).
inline void addMomentTerm(M3& A, const M3& M, const V3& d, const V3& v, M4 add) {
  const F4 di[3] = {d.x, d.y, d.z}, vj[3] = {v.x, v.y, v.z};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A.m[i][j] = add ? A.m[i][j] + (M.m[i][j] + di[i] * vj[j]) : A.m[i][j];
}
inline V3 column(const M3& a, int j) { return {a.m[0][j], a.m[1][j], a.m[2][j]}; }

// extractRotation(A, q, 1) of dynamics.cpp (Müller et al. 2016, one iteration).
inline Q4 extractRotationOnce(const M3& A, const Q4& q) {
  const M3 R = toRotationMatrix(q);
  V3 omega =
      (cross(column(R, 0), column(A, 0)) + cross(column(R, 1), column(A, 1))) + cross(column(R, 2), column(A, 2));
  const F4 dots = (dot(column(R, 0), column(A, 0)) + dot(column(R, 1), column(A, 1))) + dot(column(R, 2), column(A, 2));
  const F4 scale = abs4(dots) + 1e-9f;
  omega = {omega.x / scale, omega.y / scale, omega.z / scale};
  const F4 w = sqrt4(dot(omega, omega));
  const F4 half = 0.5f * w;
  F4 s, c;
  for (int l = 0; l < 4; ++l) {
    s[l] = std::sin(half[l]);
    c[l] = std::cos(half[l]);
  }
  const Q4 step{s * (omega.x / w), s * (omega.y / w), s * (omega.z / w), c};
  return select(w > 1e-7f, normalized(step * q), q);  // the scalar loop stops where !(w > 1e-7)
}

// Four lanes from array-of-structures data, and back.
inline F4 pack(float a, float b, float c, float d) { return F4{a, b, c, d}; }
inline V3 pack(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return {pack(a.x(), b.x(), c.x(), d.x()), pack(a.y(), b.y(), c.y(), d.y()), pack(a.z(), b.z(), c.z(), d.z())};
}

// Quaternions and matrices are contiguous floats (Eigen: x, y, z, w; a 3 × 3 matrix column
// by column): four of them go to lanes, and back, by 4 × 4 transposes of whole loads and
// stores rather than one float at a time (the moves were most of the four-lane fit's work).
inline void transpose(__m128& a, __m128& b, __m128& c, __m128& d) {
  const __m128 ab0 = _mm_unpacklo_ps(a, b), cd0 = _mm_unpacklo_ps(c, d);
  const __m128 ab1 = _mm_unpackhi_ps(a, b), cd1 = _mm_unpackhi_ps(c, d);
  a = _mm_movelh_ps(ab0, cd0), b = _mm_movehl_ps(cd0, ab0);
  c = _mm_movelh_ps(ab1, cd1), d = _mm_movehl_ps(cd1, ab1);
}
inline Q4 pack(const Quat& a, const Quat& b, const Quat& c, const Quat& d) {
  __m128 x = _mm_loadu_ps(a.coeffs().data()), y = _mm_loadu_ps(b.coeffs().data()), z = _mm_loadu_ps(c.coeffs().data()),
         w = _mm_loadu_ps(d.coeffs().data());
  transpose(x, y, z, w);
  return {F4(x), F4(y), F4(z), F4(w)};
}
inline M3 pack(const Mat3& a, const Mat3& b, const Mat3& c, const Mat3& d) {
  // Column-major: floats 0–3 are (0,0) (1,0) (2,0) (0,1), 4–7 are (1,1) (2,1) (0,2) (1,2).
  __m128 e0 = _mm_loadu_ps(a.data()), e1 = _mm_loadu_ps(b.data()), e2 = _mm_loadu_ps(c.data()),
         e3 = _mm_loadu_ps(d.data());
  transpose(e0, e1, e2, e3);
  __m128 f0 = _mm_loadu_ps(a.data() + 4), f1 = _mm_loadu_ps(b.data() + 4), f2 = _mm_loadu_ps(c.data() + 4),
         f3 = _mm_loadu_ps(d.data() + 4);
  transpose(f0, f1, f2, f3);
  M3 r;
  r.m[0][0] = F4(e0), r.m[1][0] = F4(e1), r.m[2][0] = F4(e2), r.m[0][1] = F4(e3);
  r.m[1][1] = F4(f0), r.m[2][1] = F4(f1), r.m[0][2] = F4(f2), r.m[1][2] = F4(f3);
  r.m[2][2] = pack(a(2, 2), b(2, 2), c(2, 2), d(2, 2));
  return r;
}
inline Vec3 lane(const V3& v, int l) { return Vec3(v.x[l], v.y[l], v.z[l]); }
inline Quat lane(const Q4& q, int l) { return Quat(q.w[l], q.x[l], q.y[l], q.z[l]); }
inline Mat3 lane(const M3& a, int l) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = a.m[i][j][l];
  return r;
}
// The four lanes written to four quaternions or matrices (the inverse of pack()).
inline void store(const Q4& q, Quat* a, Quat* b, Quat* c, Quat* d) {
  __m128 x = __m128(q.x), y = __m128(q.y), z = __m128(q.z), w = __m128(q.w);
  transpose(x, y, z, w);
  _mm_storeu_ps(a->coeffs().data(), x), _mm_storeu_ps(b->coeffs().data(), y);
  _mm_storeu_ps(c->coeffs().data(), z), _mm_storeu_ps(d->coeffs().data(), w);
}
inline void store(const M3& m, Mat3* a, Mat3* b, Mat3* c, Mat3* d) {
  __m128 e0 = __m128(m.m[0][0]), e1 = __m128(m.m[1][0]), e2 = __m128(m.m[2][0]), e3 = __m128(m.m[0][1]);
  transpose(e0, e1, e2, e3);
  _mm_storeu_ps(a->data(), e0), _mm_storeu_ps(b->data(), e1), _mm_storeu_ps(c->data(), e2), _mm_storeu_ps(d->data(), e3);
  __m128 f0 = __m128(m.m[1][1]), f1 = __m128(m.m[2][1]), f2 = __m128(m.m[0][2]), f3 = __m128(m.m[1][2]);
  transpose(f0, f1, f2, f3);
  _mm_storeu_ps(a->data() + 4, f0), _mm_storeu_ps(b->data() + 4, f1), _mm_storeu_ps(c->data() + 4, f2);
  _mm_storeu_ps(d->data() + 4, f3);
  (*a)(2, 2) = m.m[2][2][0], (*b)(2, 2) = m.m[2][2][1], (*c)(2, 2) = m.m[2][2][2], (*d)(2, 2) = m.m[2][2][3];
}

}  // namespace tendril::lanes
