// tendril grow with particle plants: the example scenes of seed 000's figures, numbered
// sequences (--every) and bad species settings.
#include "support/run_command.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace tendril {
namespace {

using test::quoted;

TEST(ParticleCli, TheFigureScenesAreValid) {
  auto dir = test::scratchDir();
  int scenes = 0;
  for (const auto& e : std::filesystem::directory_iterator(test::sourceDir() / "examples/scenes")) {
    if (e.path().filename().string().rfind("particles-", 0) != 0) continue;
    ++scenes;
    auto r = test::runTendril("validate " + quoted(e.path()), dir);
    EXPECT_EQ(r.exitCode, 0) << e.path() << ": " << r.err;
  }
  EXPECT_EQ(scenes, 13);  // the figure scenes, fig07 also with the position-based air and as the edit stage, fig12 in two
}

TEST(ParticleCli, GrowWritesTheEndAndANumberedSequence) {
  auto dir = test::scratchDir();
  auto r = test::runTendril("grow " + quoted(test::sourceDir() / "examples/scenes/particles-fig09-cubes.json") +
                                " -o " + quoted(dir / "out") + " --steps 120 --every 60 --format glb --quiet",
                            dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* name : {"plant_000060.glb", "plant_000120.glb", "plant.glb"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(std::filesystem::exists(dir / "out" / name));
    auto v = test::validateGltf(dir / "out" / name, dir);
    EXPECT_EQ(v.exitCode, 0) << v.out << v.err;
    EXPECT_NE(v.out.find("errors=0"), std::string::npos) << v.out;
  }
  // The last of the sequence is the end state.
  EXPECT_EQ(std::filesystem::file_size(dir / "out/plant_000120.glb"), std::filesystem::file_size(dir / "out/plant.glb"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out/plant_000030.glb"));
}

TEST(ParticleCli, BadSpeciesValuesNameFileAndPointer) {
  auto dir = test::scratchDir();
  std::filesystem::path scene = dir / "bad.json";
  {
    std::ofstream f(scene);
    f << R"({"tendril": 1, "environment": {"obstacles": [{"type": "plane", "size": [4, 4]}]},
  "plants": [{"model": "particles", "position": [0, 0.05, 0],
              "species": {"base": "ivy-particles", "stiffness": 1.5}}]})";
  }
  auto r = test::runTendril("validate " + quoted(scene), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("bad.json:/plants/0/species/stiffness"), std::string::npos) << r.err;
  std::ofstream(scene) << R"({"tendril": 1, "plants": [{"model": "particles", "position": [0, 0, 0], "species": "no-such"}]})";
  r = test::runTendril("validate " + quoted(scene), dir);
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find("unknown species \"no-such\" (built-in particles species: ivy-particles;"), std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace tendril
