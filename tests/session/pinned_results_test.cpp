// Pinned results: the content hash of one example scene per model family after a few steps.
// Any change to what these scenes grow — meant or not — fails here, so a change in results is
// always made on purpose and said in its commit. (Results are also the same for any thread
// count; tests/support/determinism.h checks that where the parallel code is.)
#include "support/test_paths.h"

#include "tendril/plant/plant_model.h"
#include "tendril/session/session.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace tendril {
namespace {

struct Pinned {
  const char* scene;  // under examples/scenes/
  uint32_t steps;     // grown this many steps (at most the scene's own, to stay quick)
  uint64_t hash;      // plant::contentHash of every plant
};

// Results are the same on every x86-64 CPU with AVX2: Embree is asked for its AVX2 kernels there
// (env/environment.cpp), the project's own AVX2 code gives the baseline's bits, and glibc's libm
// gives the same bits with and without FMA for what these scenes call (checked by turning its FMA
// and AVX2 variants off with GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA). Without that choice an
// AVX-512 machine's Embree gave other plants than an AVX2 one's (pinned 2026-12-07 as a second
// column). On a CPU without AVX2 these values do not hold.
//
// To update after a change that is meant to change results: put the value the failure reports
// here, and say in the commit which results changed and why.
constexpr Pinned kPinned[] = {
    {"default.json", 260, 0x8892da2268975053ull},                // climbing ivy (seed 003)
    {"particles-fig11-fence.json", 800, 0xd8ce953ba9eb8ed0ull},  // particle plants (seed 000)
    {"ivy-lsystem.json", 250, 0x7f797293515abdcfull},            // L-system ivy
    {"ivy-on-chestnut.json", 160, 0x604a918a8edea46cull},        // climbing ivy on a graph tree (plants as supports)
    {"garden.json", 250, 0x0b50600b802a1ab1ull},  // all four models, supports, SPH air
};

TEST(PinnedResults, ExampleScenesGrowWhatTheyGrew) {
  for (const Pinned& p : kPinned) {
    SCOPED_TRACE(p.scene);
    std::unique_ptr<session::Session> session = session::Session::open(test::sourceDir() / "examples/scenes" / p.scene);
    session->run(p.steps);
    const std::vector<plant::PlantModel> plants = session->plants();
    size_t segments = 0;
    for (const plant::PlantModel& plant : plants) segments += plant.nodeCount();
    EXPECT_GT(segments, 2000u);  // grown, not a stump
    const uint64_t hash = plant::contentHash(plants);
    EXPECT_EQ(hash, p.hash) << fmt::format(
        "examples/scenes/{} after {} steps grows other plants than it did: its content hash is now 0x{:016x}. If "
        "that is meant, pin the new value in tests/session/pinned_results_test.cpp and say in the commit what "
        "changed the results and why.",
        p.scene, p.steps, hash);
  }
}

}  // namespace
}  // namespace tendril
