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
  // plant::contentHash of every plant, as grown on each kind of machine the project runs on:
  // the same build gives other bits on another CPU (glibc's and Embree's kernels are chosen by
  // the CPU: FMA or not, vector width), so each kind has its own value. Unused entries are 0.
  uint64_t hash[2];
};

// To update after a change that is meant to change results: put the value the failure reports
// here (for the machine it ran on; say which), and say in the commit which results changed and
// why. Column 0: the machines the pins were first made on; column 1: AMD EPYC (avx2, fma),
// Debian 12 as scripts/setup installs it on 2026-12-07.
constexpr Pinned kPinned[] = {
    {"default.json", 260, {0x1367c7f3f94b5685ull, 0x11f6e5c74938df4dull}},                // climbing ivy (seed 003)
    {"particles-fig11-fence.json", 800, {0x3c65885241b8a9c0ull, 0xe6e8e4e251170fcaull}},  // particle plants (seed 000)
    {"ivy-lsystem.json", 250, {0x4ffe808bbcb75194ull, 0x4ffe808bbcb75194ull}},            // L-system ivy
    // climbing ivy on a graph tree (plants as supports)
    {"ivy-on-chestnut.json", 160, {0x74033ae4fd420a65ull, 0x42a990d5e830d9f4ull}},
    {"garden.json", 250, {0x396a9752a2cba601ull, 0x31b518512d4aec6cull}},  // all four models, supports, SPH air
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
    EXPECT_TRUE(hash == p.hash[0] || hash == p.hash[1]) << fmt::format(
        "examples/scenes/{} after {} steps grows other plants than it did: its content hash is now 0x{:016x}. If "
        "that is meant, pin the new value in tests/session/pinned_results_test.cpp and say in the commit what "
        "changed the results and why.",
        p.scene, p.steps, hash);
  }
}

}  // namespace
}  // namespace tendril
