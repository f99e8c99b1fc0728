#include "tendril/core/random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace tendril {
namespace {

TEST(Random, SameKeySameStream) {
  RandomKey k{42, 1, 7, 100, purposeId("test")};
  Rng a(k), b(k);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.nextU64(), b.nextU64());
}

TEST(Random, EveryKeyFieldChangesTheStream) {
  RandomKey base{42, 1, 7, 100, purposeId("test")};
  uint64_t first = Rng(base).nextU64();
  RandomKey k = base;
  k.seed++;
  EXPECT_NE(Rng(k).nextU64(), first);
  k = base;
  k.plant++;
  EXPECT_NE(Rng(k).nextU64(), first);
  k = base;
  k.node++;
  EXPECT_NE(Rng(k).nextU64(), first);
  k = base;
  k.step++;
  EXPECT_NE(Rng(k).nextU64(), first);
  k = base;
  k.purpose = purposeId("other");
  EXPECT_NE(Rng(k).nextU64(), first);
}

TEST(Random, UniformMomentsAndRange) {
  Rng r(RandomKey{1, 2, 3, 4, 5});
  double sum = 0, sum2 = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    float u = r.uniform();
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    sum += u;
    sum2 += double(u) * u;
  }
  double mean = sum / n, var = sum2 / n - mean * mean;
  // Standard error of the mean is 1/sqrt(12 n) ~ 6.5e-4; allow 5 sigma.
  EXPECT_NEAR(mean, 0.5, 3.3e-3);
  EXPECT_NEAR(var, 1.0 / 12.0, 2e-3);
}

TEST(Random, BelowIsUniformOverBuckets) {
  Rng r(RandomKey{9, 9, 9, 9, 9});
  int counts[7] = {};
  const int n = 70000;
  for (int i = 0; i < n; ++i) counts[r.below(7)]++;
  // Each bucket expects 10000 with sd ~ 93; allow 5 sd.
  for (int c : counts) EXPECT_NEAR(c, 10000, 470);
}

TEST(Random, UnitVectorsAreUnitAndCentred) {
  Rng r(RandomKey{3});
  Vec3 sum = Vec3::Zero();
  for (int i = 0; i < 20000; ++i) {
    Vec3 v = r.unitVector();
    ASSERT_NEAR(v.norm(), 1.0f, 1e-5f);
    sum += v;
  }
  EXPECT_LT((sum / 20000.0f).norm(), 0.03f);
}

TEST(Random, ConeStaysInside) {
  Rng r(RandomKey{4});
  Vec3 axis = Vec3(1, 1, 0).normalized();
  for (int i = 0; i < 5000; ++i) {
    Vec3 v = r.inCone(axis, radians(20));
    ASSERT_LE(angleBetween(v, axis), radians(20) + 1e-4f);
  }
}

}  // namespace
}  // namespace tendril
