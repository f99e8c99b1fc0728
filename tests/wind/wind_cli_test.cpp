// `tendril grow` with wind: the looping clip and the per-step sequence of its frames.
#include "support/run_command.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
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

// Reads a float accessor (dense) of a .glb.
std::vector<float> floatsOf(const tinygltf::Model& m, int index) {
  const tinygltf::Accessor& a = m.accessors[size_t(index)];
  const tinygltf::BufferView& v = m.bufferViews[size_t(a.bufferView)];
  const size_t components = a.type == TINYGLTF_TYPE_SCALAR ? 1 : a.type == TINYGLTF_TYPE_VEC3 ? 3 : 4;
  std::vector<float> out(a.count * components);
  std::memcpy(out.data(), m.buffers[size_t(v.buffer)].data.data() + v.byteOffset + a.byteOffset, out.size() * 4);
  return out;
}

tinygltf::Model loadGlb(const std::filesystem::path& file) {
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, file.string())) << err;
  return m;
}

TEST(WindCli, TheReadmesWindExampleMovesTheClingingIvysLeavesAndGrowsItInAClip) {
  auto dir = test::scratchDir();
  auto r = test::runTendril("grow " + quoted(test::sourceDir() / "examples/scenes/wind-gusty.json") + " -o " +
                                quoted(dir / "out") + " --steps 90 --wind-animation 1 --growth-animation 2 --format glb --quiet",
                            dir);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* name : {"plant-wind.glb", "plant-growth.glb"}) {
    SCOPED_TRACE(name);
    auto v = test::validateGltf(dir / "out" / name, dir);
    EXPECT_EQ(v.exitCode, 0) << v.out << v.err;
  }
  // The loop: ivy clinging to its wall has leaves that move (morph weights that change and
  // close the loop).
  {
    tinygltf::Model m = loadGlb(dir / "out" / "plant-wind.glb");
    ASSERT_EQ(m.animations.size(), 1u);
    int weights = 0;
    for (const tinygltf::AnimationChannel& c : m.animations[0].channels) {
      if (c.target_path != "weights") continue;
      ++weights;
      const std::vector<float> w = floatsOf(m, m.animations[0].samplers[size_t(c.sampler)].output);
      const size_t targets = m.meshes[size_t(m.nodes[size_t(c.target_node)].mesh)].weights.size();
      ASSERT_GT(targets, 0u);
      const size_t frames = w.size() / targets;
      EXPECT_TRUE(std::equal(w.begin(), w.begin() + long(targets), w.end() - long(targets))) << "the loop closes";
      EXPECT_FALSE(std::equal(w.begin(), w.begin() + long(targets), w.begin() + long((frames / 3) * targets)));
    }
    EXPECT_EQ(weights, 2) << "both ivy plants' leaves move";
  }
  // The growth clip: joints that start at scale 0 and end at 1, and leaves that move while
  // the ivy grows.
  {
    tinygltf::Model m = loadGlb(dir / "out" / "plant-growth.glb");
    ASSERT_EQ(m.animations.size(), 1u);
    int growing = 0, weights = 0;
    for (const tinygltf::AnimationChannel& c : m.animations[0].channels) {
      if (c.target_path == "weights") {
        const std::vector<float> w = floatsOf(m, m.animations[0].samplers[size_t(c.sampler)].output);
        const size_t targets = m.meshes[size_t(m.nodes[size_t(c.target_node)].mesh)].weights.size();
        ASSERT_GT(targets, 0u);
        const size_t frames = w.size() / targets;
        weights += !std::equal(w.begin(), w.begin() + long(targets), w.begin() + long((frames / 3) * targets));
      }
      if (c.target_path != "scale") continue;
      const std::vector<float> s = floatsOf(m, m.animations[0].samplers[size_t(c.sampler)].output);
      growing += s.front() < 1.0f;
      EXPECT_EQ(s.back(), 1.0f);
    }
    EXPECT_GT(growing, 20);
    EXPECT_EQ(weights, 2) << "both ivy plants' leaves move as they grow";
  }
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
