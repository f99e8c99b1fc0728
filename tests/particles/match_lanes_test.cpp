// The four-lane shape-matching arithmetic (core/match_lanes.h) gives, lane for lane, the
// same bits as the Eigen expressions of the scalar fit it stands in for: otherwise a plant's
// motion would depend on how its particles happen to fall into groups of four.
#include "tendril/core/random.h"
#include "tendril/core/match_lanes.h"
#include "tendril/particles/shape_matching.h"

#include <gtest/gtest.h>

#include <cstring>

namespace tendril::particles {
namespace {

using namespace lanes;

template <class T>
bool sameBits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

struct Inputs {
  Rng rng{RandomKey{7, 0, 0, 0, 0}};
  float scalar(float scale = 1.0f) { return scale * rng.uniform(-1.0f, 1.0f); }
  Vec3 vec(float scale = 1.0f) { return Vec3(scalar(scale), scalar(scale), scalar(scale)); }
  Quat quat() { return Quat(scalar(), scalar(), scalar(), scalar()).normalized(); }
  Mat3 mat(float scale = 1.0f) {
    Mat3 m;
    for (int k = 0; k < 9; ++k) m.data()[k] = scalar(scale);
    return m;
  }
};

TEST(MatchLanes, QuaternionAndVectorOperationsMatchEigenBitForBit) {
  Inputs in;
  for (int round = 0; round < 2000; ++round) {
    Quat a[4], b[4];
    Vec3 v[4];
    Mat3 m[4], n[4];
    for (int l = 0; l < 4; ++l) {
      a[l] = in.quat(), b[l] = in.quat(), v[l] = in.vec(3.0f), m[l] = in.mat(), n[l] = in.mat(0.01f);
      // Unnormalised quaternions, as blends are before normalisation; one of them zero.
      if (l == 3) b[l].coeffs() *= 1.7f;
    }
    if (round == 0) a[2].coeffs().setZero();
    const Q4 A = pack(a[0], a[1], a[2], a[3]), B = pack(b[0], b[1], b[2], b[3]);
    const V3 V = pack(v[0], v[1], v[2], v[3]);
    const M3 M = pack(m[0], m[1], m[2], m[3]), N = pack(n[0], n[1], n[2], n[3]);
    const Q4 product = A * B, conj = conjugate(A) * B, norm = normalized(B), zeroSafe = normalized(A);
    const V3 turned = rotate(A, V);
    const M3 rotation = toRotationMatrix(A), matProduct = M * N;
    const F4 d4 = dot4(A, B), d3 = dot(V, V);
    for (int l = 0; l < 4; ++l) {
      SCOPED_TRACE(testing::Message() << "round " << round << ", lane " << l);
      EXPECT_TRUE(sameBits(lane(product, l), Quat(a[l] * b[l])));
      EXPECT_TRUE(sameBits(lane(conj, l), Quat(a[l].conjugate() * b[l])));
      EXPECT_TRUE(sameBits(lane(norm, l), b[l].normalized()));
      EXPECT_TRUE(sameBits(lane(zeroSafe, l), a[l].normalized()));
      EXPECT_TRUE(sameBits(lane(turned, l), Vec3(a[l] * v[l])));
      EXPECT_TRUE(sameBits(lane(rotation, l), Mat3(a[l].toRotationMatrix())));
      EXPECT_TRUE(sameBits(lane(matProduct, l), Mat3(m[l] * n[l])));
      EXPECT_TRUE(sameBits(d4[l], a[l].coeffs().dot(b[l].coeffs())));
      EXPECT_TRUE(sameBits(d3[l], v[l].dot(v[l])));
    }
  }
}

TEST(MatchLanes, PackAndStoreMoveEveryFloatToItsLaneAndBack) {
  Inputs in;
  Quat q[4], qBack[4];
  Mat3 m[4], mBack[4];
  for (int l = 0; l < 4; ++l) q[l] = in.quat(), m[l] = in.mat(), qBack[l] = Quat::Identity(), mBack[l].setZero();
  const Q4 Q = pack(q[0], q[1], q[2], q[3]);
  const M3 M = pack(m[0], m[1], m[2], m[3]);
  for (int l = 0; l < 4; ++l) {
    SCOPED_TRACE(testing::Message() << "lane " << l);
    EXPECT_TRUE(sameBits(Q.x[l], q[l].x()) && sameBits(Q.y[l], q[l].y()) && sameBits(Q.z[l], q[l].z()) &&
                sameBits(Q.w[l], q[l].w()));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_TRUE(sameBits(M.m[i][j][l], m[l](i, j))) << i << ", " << j;
  }
  store(Q, &qBack[0], &qBack[1], &qBack[2], &qBack[3]);
  store(M, &mBack[0], &mBack[1], &mBack[2], &mBack[3]);
  for (int l = 0; l < 4; ++l) {
    EXPECT_TRUE(sameBits(qBack[l], q[l])) << "lane " << l;
    EXPECT_TRUE(sameBits(mBack[l], m[l])) << "lane " << l;
  }
}

TEST(MatchLanes, MomentTermsAndRotationExtractionMatchTheScalarFit) {
  Inputs in;
  for (int round = 0; round < 2000; ++round) {
    Mat3 a[4], m[4];
    Vec3 d[4], v[4];
    Quat q[4];
    for (int l = 0; l < 4; ++l) {
      a[l] = in.mat(1e-3f), m[l] = in.mat(1e-3f);
      d[l] = in.vec(0.05f), v[l] = in.vec(0.05f), q[l] = in.quat();
    }
    // A group already at rest: the extraction's step is below its threshold and q stays.
    a[1] = q[1].toRotationMatrix() * Vec3(1e-3f, 2e-3f, 1e-3f).asDiagonal();
    M3 A = pack(a[0], a[1], a[2], a[3]);
    const M4 some = {-1, 0, -1, -1};
    addMomentTerm(A, pack(m[0], m[1], m[2], m[3]), pack(d[0], d[1], d[2], d[3]), pack(v[0], v[1], v[2], v[3]), some);
    const Q4 extracted = extractRotationOnce(A, pack(q[0], q[1], q[2], q[3]));
    for (int l = 0; l < 4; ++l) {
      SCOPED_TRACE(testing::Message() << "round " << round << ", lane " << l);
      Mat3 expected = a[l];
      if (some[l]) expected += m[l] + d[l] * v[l].transpose();
      EXPECT_TRUE(sameBits(lane(A, l), expected));
      EXPECT_TRUE(sameBits(lane(extracted, l), extractRotation(expected, q[l], 1)));
    }
  }
}

}  // namespace
}  // namespace tendril::particles
