// tendril sweep SWEEP.json -o DIR and tendril batch MANIFEST.jsonl [...]: plant libraries at
// scale (docs/batch.md). Both are the Python package's tendril.batch (Dask distributed does the
// fanning out), so these commands only find Python and the package and exec
//   python3 -m tendril.batch sweep|batch ARGS...
// The exit code is Python's: 0 ok, 2 bad input, 3 some variants failed, 1 internal error.
//
// The package is looked for in $TENDRIL_PYTHON_PATH, else beside this executable
// (<dir>/python/tendril: the build tree), else in the directory `cmake --install` puts it
// (TENDRIL_PYTHON_SITE), else wherever the interpreter finds it.
#include "commands.h"

#include "tendril/core/error.h"

#include <fmt/format.h>

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#ifndef TENDRIL_PYTHON_EXECUTABLE
#define TENDRIL_PYTHON_EXECUTABLE "/usr/bin/python3"
#endif
#ifndef TENDRIL_PYTHON_SITE
#define TENDRIL_PYTHON_SITE ""
#endif

namespace tendril::cli {
namespace {

namespace fs = std::filesystem;

bool hasPackage(const fs::path& dir) {
  std::error_code ec;
  return !dir.empty() && fs::is_regular_file(dir / "tendril" / "batch.py", ec);
}

// The directory holding the package `tendril`, or "" to leave it to the interpreter.
std::string packageDir() {
  if (const char* env = std::getenv("TENDRIL_PYTHON_PATH"); env && *env) {
    if (!hasPackage(env))
      throw Error("TENDRIL_PYTHON_PATH", env, "has no Python package tendril with tendril/batch.py");
    return env;
  }
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec && hasPackage(self.parent_path() / "python")) return (self.parent_path() / "python").string();
  fs::path site = TENDRIL_PYTHON_SITE;
  if (!site.empty() && site.is_relative() && !ec) site = self.parent_path().parent_path() / site;  // <prefix>/bin/..
  if (hasPackage(site)) return site.string();
  return "";
}

[[noreturn]] void execPython(const std::string& command, const std::vector<std::string>& args) {
  const std::string dir = packageDir();
  if (!dir.empty()) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = (old && *old) ? dir + ":" + old : dir;
    setenv("PYTHONPATH", path.c_str(), 1);
  }
  const char* python = std::getenv("TENDRIL_PYTHON");
  if (!python || !*python) python = TENDRIL_PYTHON_EXECUTABLE;
  std::vector<std::string> argv = {python, "-m", "tendril.batch", command};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> raw;
  for (std::string& a : argv) raw.push_back(a.data());
  raw.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  execv(python, raw.data());
  // Only reached when the interpreter could not be started.
  throw std::runtime_error(fmt::format("cannot run {} ({}): `tendril {}` needs Debian's python3 with python3-distributed "
                                       "(scripts/setup); TENDRIL_PYTHON names another interpreter",
                                       python, std::strerror(errno), command));
}

// Every argument after the command goes to Python untouched (its argparse checks them and
// prints --help).
std::function<int()> passThrough(CLI::App& sub, const std::string& command) {
  sub.allow_extras();
  sub.set_help_flag();
  sub.positionals_at_end(false);
  return [&sub, command]() -> int { execPython(command, sub.remaining()); };
}

RegisterCommand registerSweep("sweep", "Expand a sweep file (species x seeds x parameters) into a manifest of variants", 30,
                              [](CLI::App& sub) { return passThrough(sub, "sweep"); });
RegisterCommand registerBatch("batch",
                              "Run a manifest of variants on Dask (local cluster, a scheduler, or one shard): "
                              "resumable, with a catalog and a contact sheet",
                              31, [](CLI::App& sub) { return passThrough(sub, "batch"); });

}  // namespace
}  // namespace tendril::cli
