// `tendril grow` with wind: the looping clip and the per-step sequence of its frames.
#include "support/run_command.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

namespace tendril {
namespace {

using test::quoted;

TEST(WindCli, GrowWritesTheLoopingClipAndItsFrames) {
  auto dir = test::scratchDir();
  auto r = test::runTendril("grow " + quoted(test::sourceDir() / "examples/scenes/wind-gusty.json") + " -o " +
                                quoted(dir / "out") + " --steps 60 --wind-animation 0.5 --wind-frames --format glb --quiet",
                            dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  // The scene's clip keeps its fps (24): 0.5 s is 12 frames.
  for (const char* name : {"plant.glb", "plant-wind.glb", "plant-wind_0000.glb", "plant-wind_0011.glb"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(std::filesystem::exists(dir / "out" / name));
    auto v = test::validateGltf(dir / "out" / name, dir);
    EXPECT_EQ(v.exitCode, 0) << v.out << v.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "plant-wind_0012.glb"));
}

TEST(WindCli, GrowWithSimulatedAirReportsIt) {
  auto dir = test::scratchDir();
  auto r = test::runTendril("grow " + quoted(test::sourceDir() / "examples/scenes/particles-fig07-wind.json") + " -o " +
                                quoted(dir / "out") + " --steps 8 --format glb",
                            dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("simulated air: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("at 0.05 m spacing"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ms per step on average"), std::string::npos) << r.err;
  auto v = test::validateGltf(dir / "out" / "plant.glb", dir);
  EXPECT_EQ(v.exitCode, 0) << v.out << v.err;
}

TEST(WindCli, FramesWithoutAClipAreAnErrorBeforeGrowing) {
  auto dir = test::scratchDir();
  auto r = test::runTendril("grow " + quoted(test::sourceDir() / "examples/scenes/default.json") + " -o " +
                                quoted(dir / "out") + " --wind-frames --quiet",
                            dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("--wind-frames"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "plant.glb"));
}

}  // namespace
}  // namespace tendril
