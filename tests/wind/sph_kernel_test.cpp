// Seed 000 eq. 13: a plant particle meets the air through an anisotropic kernel W(G(x − x_j))
// whose support is the particle's own ellipsoid grown by h. A screen of long, thin particles
// across a stream slows the air behind its whole width with that kernel; with an isotropic
// kernel of the particle's volume in its place (SphSettings::kernel = Isotropic, the ablation)
// the air leaks through where two long particles meet and the screen catches half the wind.
// Also: the setting is read from a scene and checked, and the ablation's results do not depend
// on the thread count.
#include "support/determinism.h"
#include "support/sph_stream.h"
#include "support/test_paths.h"
#include "tendril/core/error.h"
#include "tendril/core/hash.h"
#include "tendril/core/json_reader.h"
#include "tendril/env/environment.h"
#include "tendril/env/primitives.h"
#include "tendril/scene/scene.h"
#include "tendril/wind/sph.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace tendril::wind {
namespace {

// Bodies held still in the air (a stiff screen): only the air moves.
class Screen final : public models::AirCoupling {
 public:
  std::vector<uint32_t> ids;
  std::vector<Vec3> x, v;
  std::vector<Quat> q;
  std::vector<float> a, b, m;
  std::vector<Vec3> push;

  void add(const Vec3& centre, const Vec3& axis, float halfLength, float radius) {
    ids.push_back(uint32_t(x.size()));
    x.push_back(centre);
    v.push_back(Vec3::Zero());
    q.push_back(Quat::FromTwoVectors(Vec3::UnitY(), axis.normalized()));
    a.push_back(halfLength);
    b.push_back(radius);
    m.push_back(700.0f * 4.0f / 3.0f * kPi * halfLength * radius * radius);
  }
  models::AirBodies airBodies() const override {
    models::AirBodies B;
    B.ids = ids;
    B.position = x;
    B.velocity = v;
    B.orientation = q;
    B.halfLength = a;
    B.radius = b;
    B.mass = m;
    B.slots = x.size();
    return B;
  }
  std::vector<Vec3>& airAcceleration() override { return push; }
  float airTimeStep() const override { return 0.025f; }
};

// A screen of twenty rods 40 cm long and 4 cm thick lying across a stream along +x (their axes
// along z): ten rows stacked without gaps from y = 0.2 to 0.6 m, each row two rods end to end
// (centres at z = ∓0.2, meeting at z = 0). Each rod is one particle.
Screen rodScreen() {
  Screen s;
  for (int k = 0; k < 10; ++k)
    for (float z : {-0.2f, 0.2f}) s.add(Vec3(0, 0.22f + 0.04f * float(k), z), Vec3::UnitZ(), 0.2f, 0.02f);
  return s;
}

struct Stream {
  std::unique_ptr<env::Environment> env;
  SphSettings settings;
};

// A 5 m/s stream along +x through an open box of 4 cm air, at rest density from the start.
Stream stream(SphKernel kernel, SphSolver solver = SphSolver::PositionBased) {
  Stream t;
  t.env = std::make_unique<env::Environment>();
  t.env->commit();
  t.settings.solver = solver;
  t.settings.kernel = kernel;
  t.settings.spacing = 0.04f;  // h = 8 cm
  t.settings.domainMin = Vec3(-0.5f, 0.0f, -0.7f);
  t.settings.domainMax = Vec3(0.7f, 0.8f, 0.7f);
  return t;
}

SphAir streamingAir(const Stream& t, float speed) { return test::streamingAir(t.settings, *t.env, speed, 0.9f); }

using test::meanSpeedX;

struct Lee {
  double middle = 0, joint = 0;  // the air's slowdown behind the rods' middles and behind their joint
  double drag = 0;               // the screen's total downwind push (N)
};

// The slowdown in the screen's lee against the same stream without it, averaged over the last
// frames: behind the rods' middles (|z| from 16 to 24 cm) and behind the joint where the two
// rods of a row meet (|z| < 4 cm: 20 cm from either rod's centre, beyond the isotropic
// support's radius ∛(a b²) + h = 12.3 cm but within the rods' own length).
Lee screenLee(SphKernel kernel) {
  const Stream t = stream(kernel);
  Screen screen = rodScreen();
  SphAir coupled = streamingAir(t, 5.0f), alone = streamingAir(t, 5.0f);
  const float x0 = 0.1f, x1 = 0.3f, y0 = 0.25f, y1 = 0.55f;
  double middle = 0, middleAlone = 0, joint = 0, jointAlone = 0, drag = 0;
  const int frames = 24, averaged = 8;
  for (int frame = 0; frame < frames; ++frame) {
    coupled.step(*t.env, &screen);
    alone.step(*t.env, nullptr);
    if (frame < frames - averaged) continue;
    joint += meanSpeedX(coupled, Vec3(x0, y0, -0.04f), Vec3(x1, y1, 0.04f));
    jointAlone += meanSpeedX(alone, Vec3(x0, y0, -0.04f), Vec3(x1, y1, 0.04f));
    for (float side : {-1.0f, 1.0f}) {
      const Vec3 lo(x0, y0, side * 0.16f), hi(x1, y1, side * 0.24f);
      middle += meanSpeedX(coupled, lo, hi);
      middleAlone += meanSpeedX(alone, lo, hi);
    }
    for (size_t j = 0; j < screen.x.size(); ++j) drag += screen.push[j].x() * screen.m[j] / averaged;
  }
  return Lee{1.0 - middle / middleAlone, 1.0 - joint / jointAlone, drag};
}

TEST(SphKernel, EquationThirteensKernelLetsNoAirThroughTheJointsOfLongParticles) {
  const Lee anisotropic = screenLee(SphKernel::Anisotropic);
  const Lee isotropic = screenLee(SphKernel::Isotropic);
  std::printf("lee slowdown behind the rods' middles / their joint: anisotropic %.1f%% / %.1f%% (drag %.3f N), "
              "isotropic %.1f%% / %.1f%% (drag %.3f N)\n",
              100 * anisotropic.middle, 100 * anisotropic.joint, anisotropic.drag, 100 * isotropic.middle,
              100 * isotropic.joint, isotropic.drag);
  // Eq. 13: the screen slows the air behind its whole width, behind the rods' joint too (less
  // than behind their middles: the kernel weighs the air near a particle's centre most).
  EXPECT_GT(anisotropic.middle, 0.3) << "the air behind the rods is slowed";
  EXPECT_GT(anisotropic.joint, 0.15) << "and behind their joint";
  // An isotropic kernel of the particle's volume meets the air only around each rod's centre:
  // the air there all but stops, the stream leaks through the joint, and the screen catches
  // much less of the wind.
  EXPECT_LT(isotropic.joint, 0.5 * anisotropic.joint) << "the air leaks through the joint";
  EXPECT_GT(anisotropic.joint / anisotropic.middle, 3.0 * isotropic.joint / isotropic.middle)
      << "the isotropic slowdown stays near the rods' centres";
  EXPECT_GT(anisotropic.drag, 1.5 * isotropic.drag) << "the whole length of the rods catches the wind";
}

uint64_t isotropicRunHash(float speed) {
  Stream t = stream(SphKernel::Isotropic, SphSolver::WeaklyCompressible);
  t.settings.spacing = 0.06f;
  Screen screen = rodScreen();
  SphAir air = streamingAir(t, speed);
  for (int frame = 0; frame < 6; ++frame) air.step(*t.env, &screen);
  Hasher h;
  h.add(air.positions());
  h.add(air.velocities());
  h.add(air.densities());
  h.add(screen.push);
  return h.digest();
}

TEST(SphKernel, TheIsotropicKernelsResultsAreTheSameForAnyThreadCount) {
  const uint64_t one = test::sameAtEveryThreadCount([] { return isotropicRunHash(3.0f); });
  EXPECT_NE(one, isotropicRunHash(3.1f));
}

TEST(SphKernel, TheSceneChoosesTheKernelAndABadOneIsNamed) {
  auto parse = [](const std::string& sph) {
    const std::string json = R"({"tendril": 1, "environment": {"wind": {"mode": "sph", "sph": )" + sph + "}}}";
    return scene::parseScene(parseJson(json, "air.json"), "air.json", test::sourceDir());
  };
  const std::string box = R"("domain_min": [0, 0, 0], "domain_max": [1, 1, 1])";
  EXPECT_EQ(parse("{" + box + "}").sph.kernel, SphKernel::Anisotropic);
  EXPECT_EQ(parse("{" + box + R"(, "kernel": "anisotropic"})").sph.kernel, SphKernel::Anisotropic);
  EXPECT_EQ(parse("{" + box + R"(, "kernel": "isotropic"})").sph.kernel, SphKernel::Isotropic);
  try {
    parse("{" + box + R"(, "kernel": "spherical"})");
    ADD_FAILURE() << "an unknown kernel was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("air.json:/environment/wind/sph/kernel"), std::string::npos) << e.what();
  }
  SphSettings bad;
  bad.kernel = SphKernel(7);
  try {
    SphAir air(bad);
    ADD_FAILURE() << "a kernel out of range was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("kernel"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tendril::wind
