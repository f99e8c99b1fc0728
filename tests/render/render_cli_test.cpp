// `tendril render` end to end: the real binary on the example scene, headless.
#include "support/test_paths.h"
#include "tendril/io/image.h"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <string>

namespace tendril {
namespace {

namespace fs = std::filesystem;

// Runs the CLI with `args` (and `env` assignments before it) from `dir`; returns the exit
// code and fills `err` with what it printed on stderr.
int runCli(const fs::path& dir, const std::string& args, std::string* err, const std::string& env = "") {
  fs::path errFile = dir / "stderr.txt";
  std::string cmd = env + (env.empty() ? "" : " ") + "'" + test::cliPath().string() + "' " + args + " 2> '" + errFile.string() + "'";
  int status = std::system(cmd.c_str());
  if (err) *err = test::readText(errFile);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(RenderCli, DefaultSceneRendersWithGreenLeaves) {
  fs::path dir = test::scratchDir();
  fs::path scene = test::sourceDir() / "examples/scenes/default.json";
  fs::path bare = dir / "bare.png", grown = dir / "grown.png";
  std::string err;
  ASSERT_EQ(runCli(dir, "render '" + scene.string() + "' -o '" + bare.string() + "' --steps 0 --width 320 --height 180 -q", &err), 0) << err;
  ASSERT_EQ(runCli(dir, "render '" + scene.string() + "' -o '" + grown.string() + "' --steps 40 --width 320 --height 180 -q", &err), 0) << err;
  io::Image a = io::readImage(bare), b = io::readImage(grown);
  ASSERT_EQ(b.width, 320);
  ASSERT_EQ(b.height, 180);
  ASSERT_EQ(a.width, 320);
  // The pixels the growth changed are the plants (and their shadows on the wall, which is
  // warm grey): most of them must be leaf green.
  int changed = 0, green = 0;
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x) {
      const uint8_t* p = a.pixel(x, y);
      const uint8_t* q = b.pixel(x, y);
      int diff = std::max({std::abs(p[0] - q[0]), std::abs(p[1] - q[1]), std::abs(p[2] - q[2])});
      if (diff < 24) continue;
      ++changed;
      green += q[1] > q[0] && q[1] > q[2];
    }
  EXPECT_GT(changed, 300) << "the plants should cover a visible part of the image";
  EXPECT_GT(double(green) / double(changed), 0.6) << green << " green of " << changed << " changed pixels";
}

TEST(RenderCli, BadArgumentsAreCommandLineErrors) {
  fs::path dir = test::scratchDir();
  fs::path scene = test::sourceDir() / "examples/scenes/default.json";
  std::string err;
  EXPECT_EQ(runCli(dir, "render '" + scene.string() + "' -o '" + (dir / "x.png").string() + "' --eye 1,2", &err), 2);
  EXPECT_NE(err.find("--eye"), std::string::npos) << err;
  EXPECT_NE(err.find("three comma-separated numbers"), std::string::npos) << err;
  EXPECT_EQ(runCli(dir, "render '" + scene.string() + "' -o '" + (dir / "x.png").string() + "' --eye 1,1,1 --target 1,1,1", &err), 2);
  EXPECT_NE(err.find("same point"), std::string::npos) << err;
  EXPECT_EQ(runCli(dir, "render '" + scene.string() + "' -o '" + (dir / "x.png").string() + "' --width 8", &err), 2);
  EXPECT_FALSE(fs::exists(dir / "x.png"));
}

TEST(RenderCli, AirIsDrawnOnlyWhereThereIsAny) {
  fs::path dir = test::scratchDir();
  fs::path wind = test::sourceDir() / "examples/scenes/particles-fig07-wind.json";
  fs::path still = test::sourceDir() / "examples/scenes/default.json";
  fs::path plain = dir / "plain.png", air = dir / "air.png";
  std::string err;
  const std::string size = " --steps 4 --width 320 --height 180 -q";
  ASSERT_EQ(runCli(dir, "render '" + wind.string() + "' -o '" + plain.string() + "'" + size, &err), 0) << err;
  ASSERT_EQ(runCli(dir, "render '" + wind.string() + "' -o '" + air.string() + "' --air" + size, &err), 0) << err;
  // The streaks of the air that fills the tunnel: mostly green (the scene's 3 m/s wind).
  io::Image a = io::readImage(plain), b = io::readImage(air);
  int changed = 0, green = 0;
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x) {
      const uint8_t* p = a.pixel(x, y);
      const uint8_t* q = b.pixel(x, y);
      if (std::max({std::abs(p[0] - q[0]), std::abs(p[1] - q[1]), std::abs(p[2] - q[2])}) < 24) continue;
      ++changed;
      green += q[1] > q[0] && q[1] > q[2];
    }
  EXPECT_GT(changed, 320 * 180 / 10) << "the air covers a good part of the image";
  EXPECT_GT(double(green) / double(changed), 0.5) << green << " green of " << changed << " changed pixels";
  // A scene without simulated air: an error naming the option, and no image.
  EXPECT_EQ(runCli(dir, "render '" + still.string() + "' -o '" + (dir / "x.png").string() + "' --air" + size, &err), 2);
  EXPECT_NE(err.find("--air"), std::string::npos) << err;
  EXPECT_NE(err.find("no simulated air"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "x.png"));
}

TEST(RenderCli, WithoutOpenGLTheErrorSaysWhatWasTried) {
  // GLVND with no vendor library: no EGL implementation at all.
  fs::path dir = test::scratchDir();
  fs::path scene = test::sourceDir() / "examples/scenes/default.json";
  std::string err;
  EXPECT_EQ(runCli(dir, "render '" + scene.string() + "' -o '" + (dir / "x.png").string() + "' --steps 1 -q", &err,
                   "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json"),
            2);
  EXPECT_NE(err.find("cannot create an OpenGL 4.1+ core context"), std::string::npos) << err;
  EXPECT_NE(err.find("surfaceless"), std::string::npos) << err;
  EXPECT_NE(err.find("pbuffer"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "x.png"));
}

}  // namespace
}  // namespace tendril
