// tendril-studio end to end: the real binary, headless under xvfb-run, replaying edit scripts
// that seed, paint, drag and cut; and its command-line errors.
#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"
#include "tendril/session/edit.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"
#include "tendril/session/session_file.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>

namespace tendril {
namespace {

namespace fs = std::filesystem;

const fs::path kTestDir = TENDRIL_STUDIO_TEST_DIR;

fs::path scratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::path(TENDRIL_TEST_TMP) / (std::string(info->test_suite_name()) + "." + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// 'path', for a shell command line.
std::string quoted(const fs::path& path) {
  std::string s(1, '\'');
  s += path.string();
  s += '\'';
  return s;
}

bool haveXvfb() { return std::system("command -v xvfb-run > /dev/null 2>&1") == 0; }

// Runs the studio with `args` (under xvfb-run when `display`); returns the exit code and
// fills `out` and `err`.
int runStudio(const fs::path& dir, const std::string& args, bool display, std::string* out, std::string* err) {
  fs::path outFile = dir / "stdout.txt", errFile = dir / "stderr.txt";
  std::string cmd = std::string(display ? "xvfb-run -a -s '-screen 0 1280x1024x24' " : "") + "'" TENDRIL_STUDIO_PATH "' " +
                    args + " > '" + outFile.string() + "' 2> '" + errFile.string() + "'";
  // llvmpipe: two rasteriser threads on the 2-core CI machine.
  setenv("LP_NUM_THREADS", "2", 0);
  int status = std::system(cmd.c_str());
  if (out) *out = readText(outFile);
  if (err) *err = readText(errFile);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Leaf-green pixels inside the viewport (the window minus the side panels, menu, timeline
// and status bar; see apps/studio/panels.cpp). The pale mint of painted stroke points is not
// leaf green (too much blue).
int greenViewportPixels(const io::Image& image) {
  int green = 0;
  for (int y = 30; y < image.height - 70; ++y)
    for (int x = 290; x < image.width - 380; ++x) {
      const uint8_t* p = image.pixel(x, y);
      green += p[1] > p[0] + 12 && p[1] > p[2] + 12 && p[2] * 5 < p[1] * 4;
    }
  return green;
}

// Red pixels inside the viewport (the imported post of import.json).
int redViewportPixels(const io::Image& image) {
  int red = 0;
  for (int y = 30; y < image.height - 70; ++y)
    for (int x = 290; x < image.width - 380; ++x) {
      const uint8_t* p = image.pixel(x, y);
      red += p[0] > p[1] + 40 && p[0] > p[2] + 40;
    }
  return red;
}

// The segment count the studio reports in its last line ("..., step N, M segments").
long reportedSegments(const std::string& err) {
  std::smatch m;
  static const std::regex pattern(R"(step (\d+), (\d+) segments)");
  long segments = -1;
  for (auto it = std::sregex_iterator(err.begin(), err.end(), pattern); it != std::sregex_iterator(); ++it)
    segments = std::stol((*it)[2]);
  return segments;
}

TEST(StudioCommandLine, BadArgumentsExitTwoNamingTheArgument) {
  fs::path dir = scratchDir();
  const std::pair<std::string, std::string> cases[] = {
      {"--frames abc --screenshot x.png", "--frames"},
      {"--frames 3", "--screenshot"},
      {"--screenshot x.png", "--frames"},
      {"--frames 2 --screenshot x.jpg", "--screenshot"},
      {"--size 10x10 --frames 1 --screenshot x.png", "--size"},
      {"--bogus", "--bogus"},
      {"a.json b.json", "b.json"},
      {"--script", "--script"},
      {"--frames 1 --screenshot x.png --export x.fbx", "--export"},
      {"--restore-autosave maybe", "--restore-autosave"},
      {"--autosave-interval -1", "--autosave-interval"},
      {"--autosave-edits many", "--autosave-edits"},
  };
  for (const auto& [args, named] : cases) {
    std::string out, err;
    EXPECT_EQ(runStudio(dir, args, false, &out, &err), 2) << args;
    EXPECT_NE(err.find(named), std::string::npos) << args << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << args << ": one line expected, got: " << err;
  }
}

TEST(StudioCommandLine, MissingFilesAreErrorsNamingThem) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  std::string out, err;
  fs::path shot = dir / "x.png";
  EXPECT_EQ(runStudio(dir, quoted(dir / "missing.json") + " --frames 1 --screenshot " + quoted(shot), true, &out, &err),
            1);
  EXPECT_NE(err.find("missing.json"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(shot));
}

TEST(StudioHeadless, ReplaysSeedPaintDragCutAndShowsTheOutcome) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  const fs::path scene = kTestDir / "wall.json";
  // 75 frames × 4 steps: the cut at step 120 leaves time for the pieces to fall, rest (1 s)
  // and be removed (3 s later) at dt = 25 ms.
  const int frames = 75, speed = 4;
  auto run = [&](const std::string& script, const fs::path& png, std::string* err) {
    std::string out;
    int code = runStudio(dir,
                         quoted(scene) + " --script " + quoted(kTestDir / script) + " --frames " +
                             std::to_string(frames) + " --speed " + std::to_string(speed) + " --screenshot " +
                             quoted(png) + " --size 1200x700 --stats",
                         true, &out, err);
    EXPECT_NE(out.find("frame 0:"), std::string::npos) << out;
    return code;
  };
  fs::path cutPng = dir / "cut.png", keptPng = dir / "kept.png";
  std::string cutErr, keptErr;
  ASSERT_EQ(run("sculpt.json", cutPng, &cutErr), 0) << cutErr;
  ASSERT_EQ(run("sculpt-nocut.json", keptPng, &keptErr), 0) << keptErr;

  io::Image cut = io::readImage(cutPng), kept = io::readImage(keptPng);
  ASSERT_EQ(kept.width, 1200);
  ASSERT_EQ(kept.height, 700);
  const int keptGreen = greenViewportPixels(kept), cutGreen = greenViewportPixels(cut);
  EXPECT_GT(keptGreen, 5000) << "the seeded ivy should show its leaves in the viewport";
  EXPECT_LT(cutGreen, keptGreen / 2) << "cutting the stem low down removes most of the plant";

  // The studio applied the scripts through the library's runner one frame at a time: the
  // result is the state the runner reaches in one go.
  for (const auto& [script, err] : {std::pair{"sculpt.json", cutErr}, std::pair{"sculpt-nocut.json", keptErr}}) {
    auto session = session::Session::open(kTestDir / "wall.json");
    session::Editor editor(*session);
    session::runEditScript(editor, session::loadEditScript(kTestDir / script), frames * speed);
    EXPECT_EQ(reportedSegments(err), long(session->segmentCount())) << script << ": " << err;
  }
}

// Viewport pixels (as greenViewportPixels) that differ between two screenshots, and their
// bounding box.
struct ViewportDifference {
  int pixels = 0;
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
};
ViewportDifference viewportDifference(const io::Image& a, const io::Image& b) {
  ViewportDifference d;
  for (int y = 30; y < a.height - 70; ++y)
    for (int x = 290; x < a.width - 380; ++x) {
      const uint8_t *p = a.pixel(x, y), *q = b.pixel(x, y);
      if (std::abs(int(p[0]) - int(q[0])) + std::abs(int(p[1]) - int(q[1])) + std::abs(int(p[2]) - int(q[2])) <= 6) continue;
      ++d.pixels;
      d.x0 = std::min(d.x0, x), d.y0 = std::min(d.y0, y), d.x1 = std::max(d.x1, x), d.y1 = std::max(d.y1, y);
    }
  return d;
}

TEST(StudioHeadless, PlantsSwayInTheWindWhereTheyStand) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  const fs::path scene = kTestDir / "sway.json";
  // Paused: nothing grows, so what changes from frame 20 to frame 32 is the wind's motion.
  auto shot = [&](int frames, const std::string& extra, const std::string& name) {
    std::string out, err;
    EXPECT_EQ(runStudio(dir,
                        quoted(scene) + " --paused --frames " + std::to_string(frames) + " --size 1200x700 " + extra +
                            " --screenshot " + quoted(dir / name),
                        true, &out, &err),
              0)
        << err;
    return io::readImage(dir / name);
  };
  const io::Image a = shot(20, "", "a.png"), b = shot(32, "", "b.png");
  const io::Image stillA = shot(20, "--no-sway", "still-a.png"), stillB = shot(32, "--no-sway", "still-b.png");
  ASSERT_EQ(a.width, 1200);
  const int leaves = greenViewportPixels(stillA);
  ASSERT_GT(leaves, 2000) << "the willow's leaves are in view";
  EXPECT_EQ(viewportDifference(stillA, stillB).pixels, 0) << "without sway a paused scene does not change";
  const ViewportDifference moved = viewportDifference(a, b);
  EXPECT_GT(moved.pixels, leaves / 20) << "the willow sways and its leaves move";
  // ... and only where the plant (and its shadow under it) is: the box of the changed pixels
  // lies within the box of the plant in either frame, widened by a tenth of the viewport.
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
  for (const io::Image* image : {&a, &b, &stillA})
    for (int y = 30; y < image->height - 70; ++y)
      for (int x = 290; x < image->width - 380; ++x) {
        const uint8_t* p = image->pixel(x, y);
        if (p[1] > p[0] + 12 && p[1] > p[2] + 12 && p[2] * 5 < p[1] * 4)
          x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      }
  const int margin = (a.width - 290 - 380) / 10;
  EXPECT_GE(moved.x0, x0 - margin);
  EXPECT_LE(moved.x1, x1 + margin);
  EXPECT_GE(moved.y0, y0 - margin);
  EXPECT_LE(moved.y1, y1 + margin);
}

TEST(StudioHeadless, ShowsTheSimulatedAir) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  // The wind-tunnel example after two steps: its plants are seeds, what fills the viewport is
  // the air's streaks, green at the scene's 3 m/s.
  const fs::path scene = kTestDir / "../../../examples/scenes/particles-fig07-wind.json";
  std::string out, err;
  ASSERT_EQ(runStudio(dir, quoted(scene) + " --frames 2 --size 1200x700 --screenshot " + quoted(dir / "air.png"), true,
                      &out, &err),
            0)
      << err;
  EXPECT_GT(greenViewportPixels(io::readImage(dir / "air.png")), 20000);
}

// Amber pixels in the status bar (the bottom 26 pixels): where it names a plant that stopped.
int amberStatusPixels(const io::Image& image) {
  int amber = 0;
  for (int y = image.height - 26; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.pixel(x, y);
      amber += p[0] > 180 && p[1] > 130 && p[1] < p[0] && p[2] < 110;
    }
  return amber;
}

TEST(StudioHeadless, StatusBarNamesAPlantThatStoppedEarly) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  // Ivy by a wall, and ivy 1.5 m in front of it with nothing to climb.
  auto scene = [](const char* second) {
    return std::string(R"({"tendril": 1, "environment": {"obstacles": [
        {"name": "ground", "type": "plane", "size": [4, 4]},
        {"name": "wall", "type": "wall", "size": [2, 1.5, 0.1], "position": [0, 0, -0.05]}]},
        "plants": [{"name": "by-the-wall", "position": [0, 0, 0.05]}, )") + second + "]}";
  };
  std::ofstream(dir / "lost.json") << scene(R"({"name": "lost", "position": [0.5, 0, 1.5]})");
  std::ofstream(dir / "fine.json") << scene(R"({"name": "also-fine", "position": [-0.5, 0, 0.05]})");
  std::string out, err;
  ASSERT_EQ(runStudio(dir, quoted(dir / "lost.json") + " --frames 40 --size 1200x700 --screenshot " +
                               quoted(dir / "lost.png"), true, &out, &err),
            0)
      << err;
  EXPECT_NE(err.find("warning: plant \"lost\" stopped growing"), std::string::npos) << err;
  EXPECT_NE(err.find("no support in reach"), std::string::npos) << err;
  EXPECT_EQ(err.find("by-the-wall"), std::string::npos) << err;
  const int amber = amberStatusPixels(io::readImage(dir / "lost.png"));
  EXPECT_GT(amber, 200);
  ASSERT_EQ(runStudio(dir, quoted(dir / "fine.json") + " --frames 40 --size 1200x700 --screenshot " +
                               quoted(dir / "fine.png"), true, &out, &err),
            0)
      << err;
  EXPECT_EQ(err.find("stopped growing"), std::string::npos) << err;
  EXPECT_LT(amberStatusPixels(io::readImage(dir / "fine.png")), amber / 10);
}

TEST(StudioHeadless, SavedSessionReopensWhereItStopped) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  const fs::path saved = dir / "sculpt.tses";
  std::string out, err;
  ASSERT_EQ(runStudio(dir,
                      quoted(kTestDir / "wall.json") + " --script " + quoted(kTestDir / "sculpt-nocut.json") +
                          " --frames 30 --speed 4 --size 800x600 --screenshot " + quoted(dir / "a.png") +
                          " --save-session " + quoted(saved) + " --export " + quoted(dir / "plants.glb"),
                      true, &out, &err),
            0)
      << err;
  const long before = reportedSegments(err);
  ASSERT_GT(before, 0) << err;
  ASSERT_TRUE(fs::exists(saved));
  // File > Export writes the plants with the CLI's exporter: a binary glTF.
  ASSERT_TRUE(fs::exists(dir / "plants.glb"));
  EXPECT_EQ(readText(dir / "plants.glb").substr(0, 4), "glTF");
  EXPECT_GT(fs::file_size(dir / "plants.glb"), 10000u);
  ASSERT_EQ(runStudio(dir, quoted(saved) + " --frames 0 --size 800x600 --screenshot " + quoted(dir / "b.png"), true,
                      &out, &err),
            0)
      << err;
  EXPECT_EQ(reportedSegments(err), before) << err;
  EXPECT_NE(err.find("step 120,"), std::string::npos) << err;
}

TEST(StudioHeadless, ImportsAndScalesASupportMesh) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  const fs::path scene = kTestDir / "wall.json", saved = dir / "import.tses";
  std::string out, err;
  ASSERT_EQ(runStudio(dir,
                      quoted(scene) + " --script " + quoted(kTestDir / "import.json") +
                          " --frames 20 --speed 2 --size 1000x700 --select obstacle:2 --screenshot " +
                          quoted(dir / "import.png") + " --save-session " + quoted(saved),
                      true, &out, &err),
            0)
      << err;
  ASSERT_EQ(runStudio(dir, quoted(scene) + " --frames 0 --size 1000x700 --screenshot " + quoted(dir / "plain.png"),
                      true, &out, &err),
            0)
      << err;
  const int imported = redViewportPixels(io::readImage(dir / "import.png"));
  const int plain = redViewportPixels(io::readImage(dir / "plain.png"));
  EXPECT_GT(imported, 600) << "the imported red post should show in the viewport (behind the climber)";
  EXPECT_LT(plain, 100);

  // The session keeps the imported, rescaled post; the climber seeded at its foot went up it.
  session::LoadedSession loaded = session::loadSession(saved);
  const session::Session& s = *loaded.session;
  ASSERT_EQ(s.environment().obstacleCount(), 3u);
  EXPECT_EQ(s.environment().obstacle(2).name, "post");
  EXPECT_EQ(s.obstaclePath(2), "post.obj");
  EXPECT_EQ(s.obstacleScale(2), Vec3(1, 1.3f, 1));
  EXPECT_NEAR(s.environment().obstacle(2).worldBounds.max.y(), 1.3f, 1e-5f);
  ASSERT_EQ(s.plantCount(), 1u);
  float top = 0.0f;
  const plant::PlantModel climber = s.plants()[0];
  for (size_t n = 0; n < climber.nodeCount(); ++n) top = std::max(top, climber.tip(n).y());
  EXPECT_GT(top, 0.1f);

  // A mesh file that is not there: exit 1, one line naming it.
  EXPECT_EQ(runStudio(dir,
                      quoted(scene) + " --script " + quoted(kTestDir / "import-missing.json") +
                          " --frames 2 --screenshot " + quoted(dir / "missing.png"),
                      true, &out, &err),
            1);
  EXPECT_NE(err.find("no-such-post.obj"), std::string::npos) << err;
  EXPECT_NE(err.find("/edits/0"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "missing.png"));
}

// The p-graph and L-system editors' edits (set_graph, set_grammar) replayed headless: the
// edited graph plant shows its six bigger buds, and the session holds both edits.
TEST(StudioHeadless, GraphAndGrammarEditsReplay) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  const fs::path scene = kTestDir / "fig2.json", saved = dir / "edits.tses";
  std::string out, editedErr, plainErr;
  ASSERT_EQ(runStudio(dir,
                      quoted(scene) + " --script " + quoted(kTestDir / "plant-edits.json") +
                          " --frames 8 --size 1000x700 --select plant:0 --screenshot " + quoted(dir / "edited.png") +
                          " --save-session " + quoted(saved),
                      true, &out, &editedErr),
            0)
      << editedErr;
  ASSERT_EQ(runStudio(dir,
                      quoted(scene) + " --frames 8 --size 1000x700 --select plant:0 --screenshot " +
                          quoted(dir / "plain.png"),
                      true, &out, &plainErr),
            0)
      << plainErr;
  const int edited = redViewportPixels(io::readImage(dir / "edited.png"));
  const int plain = redViewportPixels(io::readImage(dir / "plain.png"));
  EXPECT_GT(plain, 50) << "fig. 2's three buds";
  EXPECT_GT(edited, 3 * plain) << "six buds, each about twice as large";

  session::LoadedSession loaded = session::loadSession(saved);
  const session::Session& s = *loaded.session;
  ASSERT_EQ(s.plantCount(), 2u);
  EXPECT_EQ(s.plantDescription(0)["graph_document"]["components"][1]["params"]["count"], 6);
  EXPECT_EQ(s.plants()[0].primitives.size(), 6u);
  EXPECT_TRUE(s.plantDescription(1).contains("grammar_text"));
  EXPECT_EQ(s.plantDescription(1)["derivation_length"], 3);
  // The studio's plants are those the library's runner makes from the same script.
  auto reference = session::Session::open(scene);
  session::Editor editor(*reference);
  session::runEditScript(editor, session::loadEditScript(kTestDir / "plant-edits.json"), 8);
  EXPECT_EQ(reportedSegments(editedErr), long(reference->segmentCount())) << editedErr;
  EXPECT_EQ(reference->stateHash(), s.stateHash());
}


TEST(StudioHeadless, ExportUsesTheScenesOutputSettings) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  // A graph plant (it does not grow: the frame count does not matter) on a box, written with
  // 5 vertices around each stem, 2 samples per segment, the obstacles, two levels of detail,
  // engine wind data and the Pivot Painter textures.
  const std::string graph = (fs::path(TENDRIL_EXAMPLES_DIR) / "graphs/sunflower.json").string();
  std::ofstream(dir / "scene.json") << R"({"tendril": 1, "environment": {"obstacles": [{"name": "base", "type": "box",
      "size": [1, 0.2, 1], "position": [0, -0.1, 0]}]}, "output": {"radial_segments": 5, "subdivisions": 2,
      "include_obstacles": true, "lods": 2, "wind_data": true, "pivot_painter": true},
      "plants": [{"name": "sunflower", "model": "graph", "graph": ")" + graph + R"(", "position": [0, 0, 0]}]})";
  std::string out, err;
  ASSERT_EQ(runStudio(dir,
                      quoted(dir / "scene.json") + " --frames 1 --size 400x300 --screenshot " + quoted(dir / "a.png") +
                          " --export " + quoted(dir / "plants.glb"),
                      true, &out, &err),
            0)
      << err;
  // What tendril grow writes for the scene (session::writePlantFiles): the same bytes, the
  // Pivot Painter textures beside the .glb included.
  session::Session s(scene::loadScene(dir / "scene.json"));
  fs::create_directories(dir / "grow");
  io::ExportScene scene;
  const std::vector<std::string> files = session::writePlantFiles(s, dir / "grow", "plants", {"glb"}, "scene.json", scene);
  ASSERT_EQ(scene.meshes.size(), 1u);
  ASSERT_EQ(files.size(), 3u);  // the two textures and the .glb
  for (const std::string& file : files) {
    const fs::path name = fs::path(file).filename();
    SCOPED_TRACE(name.string());
    ASSERT_TRUE(fs::exists(dir / name));
    EXPECT_TRUE(readText(dir / name) == readText(file));
  }
  const std::string exported = readText(dir / "plants.glb");
  EXPECT_GT(exported.size(), 10000u);
  // The default settings would have written other bytes.
  io::writeGlb(scene, dir / "default.glb");
  EXPECT_FALSE(exported == readText(dir / "default.glb"));
}

// Runs the studio with `args` under xvfb-run until its stdout (--stats) reports frame `frame`,
// then SIGKILLs the studio itself (not xvfb-run: a shell between them records its pid), as a
// crash would end it. Returns false when it ended or stalled before.
bool runStudioAndKill(const fs::path& dir, const std::string& args, int frame, std::string* err) {
  const fs::path out = dir / "stdout.txt", errFile = dir / "stderr.txt", pidFile = dir / "studio.pid";
  fs::remove(pidFile);
  std::ofstream(dir / "run.sh") << "'" TENDRIL_STUDIO_PATH "' " << args << " > " << quoted(out) << " 2> "
                                << quoted(errFile) << " &\necho $! > " << quoted(pidFile) << "\nwait $!\n";
  setenv("LP_NUM_THREADS", "2", 0);
  const std::string cmd =
      "xvfb-run -a -s '-screen 0 1280x1024x24' sh " + quoted(dir / "run.sh") + " 2> " + quoted(dir / "xvfb.txt");
  const pid_t shell = ::fork();
  if (shell == 0) {
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const std::string wanted = "frame " + std::to_string(frame) + ":";
  bool reached = false;
  pid_t studio = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(90);
  while (std::chrono::steady_clock::now() < deadline) {
    if (studio == 0) studio = pid_t(std::atol(readText(pidFile).c_str()));
    if (studio > 0 && readText(out).find(wanted) != std::string::npos) {
      reached = true;
      break;
    }
    if (::waitpid(shell, nullptr, WNOHANG) == shell) {
      if (err) *err = readText(errFile);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (studio > 0) ::kill(studio, SIGKILL);
  ::waitpid(shell, nullptr, 0);
  if (err) *err = readText(errFile);
  return reached;
}

size_t editCount(const std::vector<session::TimedEdit>& journal) {
  return size_t(std::count_if(journal.begin(), journal.end(), [](const session::TimedEdit& e) {
    return !std::holds_alternative<session::Step>(e.edit);
  }));
}

// The autosave of a studio that is killed holds the session as of its last autosave, and the
// next start restores it (or discards it); a clean exit removes it.
TEST(StudioAutosave, RestoresTheSessionOfAKilledStudio) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  const fs::path scene = kTestDir / "wall.json", script = kTestDir / "sculpt-nocut.json";
  const fs::path autosave = dir / "state/autosave.tses";
  // An autosave after every edit and none on the clock: the last one follows the drag's end at
  // step 100 (frame 24; autosaves wait for a drag to end), and the studio is killed at frame 40.
  std::string err;
  ASSERT_TRUE(runStudioAndKill(dir,
                               quoted(scene) + " --script " + quoted(script) +
                                   " --frames 100000 --speed 4 --size 800x600 --stats --screenshot " +
                                   quoted(dir / "never.png") + " --autosave " + quoted(autosave) +
                                   " --autosave-edits 1 --autosave-interval 0",
                               40, &err))
      << err;
  EXPECT_FALSE(fs::exists(dir / "never.png"));
  ASSERT_TRUE(fs::exists(autosave)) << err;
  EXPECT_NE(err.find("autosaved"), std::string::npos) << err;
  const std::string autosaved = readText(autosave);
  session::LoadedSession loaded = session::loadSession(autosave);
  const session::Session& s = *loaded.session;
  EXPECT_EQ(s.stepCount(), 100u);
  EXPECT_EQ(editCount(loaded.journal), 5u) << "seed, paint, drag begin, move and end";
  // The state the library's runner reaches with the same script in as many steps.
  {
    auto reference = session::Session::open(scene);
    session::Editor editor(*reference);
    session::runEditScript(editor, session::loadEditScript(script), s.stepCount());
    EXPECT_EQ(reference->segmentCount(), s.segmentCount());
    EXPECT_EQ(reference->stateHash(), s.stateHash());
  }
  ASSERT_GT(s.segmentCount(), 0u);

  // The next start (on the bare wall) restores it, as File > Open would: the saved session is
  // the autosave's, and the clean exit removes the autosave.
  std::string out;
  const fs::path restored = dir / "restored.tses";
  ASSERT_EQ(runStudio(dir,
                      quoted(scene) + " --frames 0 --size 800x600 --stats --screenshot " + quoted(dir / "b.png") +
                          " --autosave " + quoted(autosave) + " --restore-autosave yes --save-session " +
                          quoted(restored),
                      true, &out, &err),
            0)
      << err;
  EXPECT_NE(err.find("an autosave from"), std::string::npos) << err;
  EXPECT_NE(err.find("restored the session autosaved at"), std::string::npos) << err;
  EXPECT_EQ(reportedSegments(err), long(s.segmentCount())) << err;
  EXPECT_EQ(session::loadSession(restored).session->stateHash(), s.stateHash());
  EXPECT_FALSE(fs::exists(autosave)) << "a clean exit removes the autosave";

  // Unanswered (the dialog stays open in a headless run), it is kept for the next start, and
  // nothing is autosaved over it meanwhile.
  std::ofstream(autosave, std::ios::binary) << autosaved;
  ASSERT_EQ(runStudio(dir,
                      quoted(scene) + " --script " + quoted(script) +
                          " --frames 8 --speed 4 --size 800x600 --screenshot " + quoted(dir / "c.png") +
                          " --autosave " + quoted(autosave) + " --autosave-edits 1",
                      true, &out, &err),
            0)
      << err;
  EXPECT_NE(err.find("an autosave from"), std::string::npos) << err;
  EXPECT_EQ(err.find("autosaved"), std::string::npos) << err;
  EXPECT_TRUE(readText(autosave) == autosaved);

  // Another studio holding the autosave's lock: it is left alone, neither offered nor removed.
  {
    const int lock = ::open((autosave.string() + ".lock").c_str(), O_RDWR | O_CLOEXEC);
    ASSERT_GE(lock, 0);
    ASSERT_EQ(::flock(lock, LOCK_EX | LOCK_NB), 0);
    ASSERT_EQ(runStudio(dir,
                        quoted(scene) + " --frames 0 --size 800x600 --screenshot " + quoted(dir / "d.png") +
                            " --autosave " + quoted(autosave) + " --restore-autosave yes",
                        true, &out, &err),
              0)
        << err;
    ::close(lock);
    EXPECT_NE(err.find("in use by another tendril-studio"), std::string::npos) << err;
    EXPECT_EQ(reportedSegments(err), 0) << err;
    EXPECT_TRUE(readText(autosave) == autosaved);
  }

  // Discarded: the scene opened as given, the autosave gone.
  ASSERT_EQ(runStudio(dir,
                      quoted(scene) + " --frames 0 --size 800x600 --screenshot " + quoted(dir / "e.png") +
                          " --autosave " + quoted(autosave) + " --restore-autosave no",
                      true, &out, &err),
            0)
      << err;
  EXPECT_NE(err.find("discarded the session autosaved at"), std::string::npos) << err;
  EXPECT_EQ(reportedSegments(err), 0) << err;
  EXPECT_FALSE(fs::exists(autosave));
}

TEST(StudioAutosave, ACleanExitRemovesTheAutosave) {
  if (!haveXvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  fs::path dir = scratchDir();
  const fs::path autosave = dir / "autosave.tses";
  std::string out, err;
  ASSERT_EQ(runStudio(dir,
                      quoted(kTestDir / "wall.json") + " --script " + quoted(kTestDir / "sculpt-nocut.json") +
                          " --frames 30 --speed 4 --size 800x600 --screenshot " + quoted(dir / "a.png") +
                          " --autosave " + quoted(autosave) + " --autosave-edits 2 --autosave-interval 0",
                      true, &out, &err),
            0)
      << err;
  // Autosaved along the way (after the seed and the stroke, then after the drag), then removed.
  EXPECT_NE(err.find("autosaved " + autosave.string() + " (step 12)"), std::string::npos) << err;
  EXPECT_NE(err.find("autosaved " + autosave.string() + " (step 100)"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(autosave));
  // Headless runs autosave only when asked: nothing under $XDG_STATE_HOME (the default place).
  const char* state = std::getenv("XDG_STATE_HOME");
  const std::string previous = state ? state : "";
  setenv("XDG_STATE_HOME", (dir / "state").c_str(), 1);
  const int code = runStudio(dir,
                             quoted(kTestDir / "wall.json") + " --script " + quoted(kTestDir / "sculpt-nocut.json") +
                                 " --frames 2 --size 800x600 --autosave-edits 1 --screenshot " + quoted(dir / "b.png"),
                             true, &out, &err);
  if (state) setenv("XDG_STATE_HOME", previous.c_str(), 1);
  else unsetenv("XDG_STATE_HOME");
  ASSERT_EQ(code, 0) << err;
  EXPECT_EQ(err.find("autosave"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "state"));
}

}  // namespace
}  // namespace tendril
