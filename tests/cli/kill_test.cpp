// Killing `tendril grow` and `tendril edit` at any moment harms no output: after a SIGKILL at a
// random point of a run over a directory that holds a previous complete output, every output
// file there is byte for byte either the old file or the complete new one (io::AtomicFileWriter
// writes a temporary beside the target and renames it over the target only when complete).
//
// The temporaries a killed run leaves are named `.<output>.<pid>-<n>.tmp` (hidden, beside the
// output they were to replace, the pid of the killed process): they are not outputs, and nothing
// reads them. They stay until removed by hand; a later run does not clean them up.
#include "support/run_command.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <random>
#include <regex>
#include <string>
#include <thread>
#include <vector>

namespace tendril {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using test::quoted;

// A directory's files (not the hidden temporaries): name → bytes.
using Files = std::map<std::string, std::string>;

bool isTemporaryName(const std::string& name) { return !name.empty() && name[0] == '.'; }

Files readOutputs(const fs::path& dir) {
  Files files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (!isTemporaryName(name)) files[name] = test::readText(e.path());
  }
  return files;
}

void restore(const fs::path& dir, const Files& files) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const auto& [name, bytes] : files) test::writeText(dir / name, bytes);
}

// Starts the CLI with `args` (no shell: the pid is the CLI's own), its output thrown away.
pid_t spawnTendril(const std::vector<std::string>& args) {
  std::vector<std::string> full = {test::cliPath().string()};
  full.insert(full.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : full) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

// The temporaries in `dir` (see the top of the file): the name of the output each is for.
const std::regex kTemporary(R"(\.(.+)\.(\d+)-\d+\.tmp)");

std::vector<std::string> temporariesFor(const fs::path& dir) {
  std::vector<std::string> outputs;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    std::smatch m;
    if (std::regex_match(name, m, kTemporary)) outputs.push_back(m[1].str());
  }
  return outputs;
}

// A run to its end: how long it took, and while each output's temporary was seen (its write),
// in seconds from the start.
struct Timing {
  double total = 0.0;
  std::map<std::string, std::pair<double, double>> writes;
};

Timing timeRun(const std::vector<std::string>& args, const fs::path& out) {
  const Clock::time_point start = Clock::now();
  const pid_t pid = spawnTendril(args);
  EXPECT_GT(pid, 0);
  Timing t;
  int status = 0;
  for (;;) {
    if (::waitpid(pid, &status, WNOHANG) == pid) break;
    const double now = std::chrono::duration<double>(Clock::now() - start).count();
    for (const std::string& output : temporariesFor(out)) {
      auto [it, first] = t.writes.try_emplace(output, now, now);
      it->second.second = now;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
  t.total = std::chrono::duration<double>(Clock::now() - start).count();
  return t;
}

uint32_t readU32(const std::string& bytes, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;
}

// In `dir`, runs `make(out, steps)` once with `oldSteps` (the previous output) and once with
// `newSteps` (the reference), then `kills` times over a copy of the previous output, SIGKILLed
// after a random delay: half of them uniformly over the whole run (and a little past it), half while
// one of the outputs, picked at random, is written. Checks every file left in the directory.
void killAtRandomPoints(const fs::path& dir, const std::string& what,
                        const std::function<std::vector<std::string>(const fs::path&, int)>& make, int oldSteps,
                        int newSteps, int kills, uint64_t seed) {
  const fs::path out = dir / "out";
  auto runToEnd = [&](const fs::path& target, int steps) {
    fs::create_directories(target);
    const pid_t pid = spawnTendril(make(target, steps));
    int status = 0;
    ::waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << what << ": status " << status;
    return readOutputs(target);
  };
  const Files before = runToEnd(dir / "old", oldSteps);
  const Files after = runToEnd(dir / "new", newSteps);
  ASSERT_EQ(before.size(), after.size());
  for (const auto& [name, bytes] : after) ASSERT_TRUE(before.count(name)) << name << ": only in the new output";
  for (const char* name : {"plant.glb", "plant.obj"}) {
    ASSERT_TRUE(before.count(name) && after.count(name)) << name;
    ASSERT_NE(before.at(name), after.at(name)) << name << ": old and new must differ for the test to tell them apart";
  }

  // A timed run over the old output: its duration, when each output is written, and that it
  // gives the reference's bytes (runs are deterministic).
  restore(out, before);
  const Timing timing = timeRun(make(out, newSteps), out);
  ASSERT_TRUE(readOutputs(out) == after) << what << ": a second run gave other bytes";
  EXPECT_TRUE(temporariesFor(out).empty()) << what << ": a complete run leaves no temporaries";
  ASSERT_FALSE(timing.writes.empty()) << what << ": no write was seen";
  std::vector<std::string> written;  // the outputs whose writes the timed run saw
  for (const auto& [output, seen] : timing.writes) written.push_back(output);

  std::mt19937_64 random(seed);
  int interrupted = 0;  // kills that found a write under way (a temporary) or a mix of old and new
  for (int k = 0; k < kills; ++k) {
    // Even kills: a time of the whole run. Odd ones: a time within the write of one output,
    // counted from when its temporary appears (what comes before takes longer or shorter with
    // the machine's load), up to a little longer than the timed run took to write it.
    const bool inWrite = k % 2 == 1;
    const std::string target = written[std::uniform_int_distribution<size_t>(0, written.size() - 1)(random)];
    const double span = timing.writes.at(target).second - timing.writes.at(target).first;
    const double delay = inWrite ? std::uniform_real_distribution<double>(0.0, 1.2 * span + 1e-3)(random)
                                 : std::uniform_real_distribution<double>(0.0, 1.1 * timing.total)(random);
    SCOPED_TRACE(testing::Message() << what << ": kill " << k << " after " << delay << " s of "
                                    << (inWrite ? "writing " + target : std::string("the run"))
                                    << " (the timed run took " << timing.total << " s)");
    restore(out, before);
    Clock::time_point start = Clock::now();
    const pid_t pid = spawnTendril(make(out, newSteps));
    ASSERT_GT(pid, 0);
    int status = 0;
    bool ended = false;
    if (inWrite) {
      for (;;) {
        const std::vector<std::string> writing = temporariesFor(out);
        if (std::find(writing.begin(), writing.end(), target) != writing.end()) break;
        if (::waitpid(pid, &status, WNOHANG) == pid) {
          ended = true;  // wrote it between two looks
          break;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      }
      start = Clock::now();
    }
    if (!ended) {
      std::this_thread::sleep_until(start + std::chrono::duration<double>(delay));
      ::kill(pid, SIGKILL);
      ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    }
    const bool killed = WIFSIGNALED(status);
    if (!killed) {
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
    }

    int olds = 0, news = 0, temporaries = 0;
    for (const auto& e : fs::directory_iterator(out)) {
      const std::string name = e.path().filename().string();
      std::smatch m;
      if (std::regex_match(name, m, kTemporary)) {
        // A write the kill interrupted: a temporary of one of the outputs, of this process.
        EXPECT_TRUE(killed) << name << ": a run that completed left a temporary";
        EXPECT_TRUE(after.count(m[1].str())) << name << ": a temporary of no output";
        EXPECT_EQ(std::stol(m[2].str()), long(pid)) << name;
        ++temporaries;
        continue;
      }
      ASSERT_FALSE(isTemporaryName(name)) << name << ": a hidden file that is no temporary of the writer";
      ASSERT_TRUE(after.count(name)) << name << ": not an output";
      const std::string bytes = test::readText(e.path());
      const bool isOld = bytes == before.at(name), isNew = bytes == after.at(name);
      EXPECT_TRUE(isOld || isNew) << name << ": " << bytes.size() << " bytes, neither the old file ("
                                  << before.at(name).size() << " bytes) nor the new one (" << after.at(name).size()
                                  << " bytes)";
      if (isOld != isNew) ++(isOld ? olds : news);
      if (name.size() > 4 && name.substr(name.size() - 4) == ".glb") {
        // A complete binary glTF: its header's length is the file's.
        ASSERT_GE(bytes.size(), 12u) << name;
        EXPECT_EQ(bytes.substr(0, 4), "glTF") << name;
        EXPECT_EQ(readU32(bytes, 8), bytes.size()) << name;
      }
    }
    // Outputs are never removed: every one is still there, old or new.
    size_t present = 0;
    for (const auto& [name, bytes] : after) present += fs::exists(out / name);
    EXPECT_EQ(present, after.size());
    if (!killed) {
      EXPECT_TRUE(readOutputs(out) == after) << "a run that completed must leave the new output";
    }
    if (temporaries > 0 || (olds > 0 && news > 0)) ++interrupted;
  }
  // The kills reached the writing, where there is something to harm (else the test above
  // checks nothing): half of them are aimed at writes.
  EXPECT_GT(interrupted, 0) << what << ": no kill fell while the outputs were being written";
}

// A small wall with an ivy in gusty wind: about a second of growth for 120 steps, then
// plant.glb, plant.obj (+ .mtl and textures) and a 1 s wind clip, plant-wind.glb.
const char* kWindyWall = R"({"tendril": 1, "seed": 3, "steps": 120,
  "environment": {"obstacles": [{"type": "plane"}, {"name": "wall", "type": "wall", "size": [2, 2, 0.2]}],
                  "lights": [{"type": "directional"}],
                  "wind": {"mode": "gusty", "velocity": [6, 0, 0], "gust_strength": 0.4, "gust_period": 3, "seed": 5}},
  "plants": [{"name": "ivy", "position": [0, 0, 0.12]}],
  "output": {"wind_animation": {"seconds": 1, "fps": 24, "joints": 64}}})";

TEST(CliKill, GrowLeavesEveryOutputOldOrNew) {
  const fs::path dir = test::scratchDir(), scene = dir / "scene.json";
  test::writeText(scene, kWindyWall);
  killAtRandomPoints(
      dir, "grow",
      [&](const fs::path& out, int steps) {
        return std::vector<std::string>{"grow", scene.string(), "-o", out.string(), "--steps", std::to_string(steps),
                                        "--wind-animation", "1", "-q", "--threads", "2"};
      },
      60, 120, 24, 20240601);
}

TEST(CliKill, EditLeavesEveryOutputOldOrNew) {
  // The edit stage's script (seed, paint, drag, cut, move), then growth to 400 steps; the
  // session is saved into the output directory too.
  const fs::path scene = test::sourceDir() / "examples/scenes/edit-stage.json";
  const fs::path script = test::sourceDir() / "examples/edits/edit-stage.json";
  killAtRandomPoints(
      test::scratchDir(), "edit",
      [&](const fs::path& out, int steps) {
        return std::vector<std::string>{"edit",  scene.string(), "--script", script.string(), "-o", out.string(),
                                        "--steps", std::to_string(steps), "--save", (out / "edit.tses").string(),
                                        "-q"};
      },
      60, 400, 24, 20240602);
}

}  // namespace
}  // namespace tendril
