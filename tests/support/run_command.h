// Runs a command line through the shell and captures its exit code, stdout and stderr.
#pragma once

#include "support/test_paths.h"

#include <sys/wait.h>

#include <cstdlib>
#include <string>

namespace tendril::test {

struct CommandResult {
  int exitCode = -1;
  std::string out, err;
};

inline CommandResult runCommand(const std::string& command, const std::filesystem::path& scratch) {
  std::filesystem::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  std::string full = command + " > '" + out.string() + "' 2> '" + err.string() + "'";
  int status = std::system(full.c_str());
  CommandResult r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readText(out);
  r.err = readText(err);
  return r;
}

inline std::string quoted(const std::filesystem::path& p) {
  // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) about "'" + string&&.
  std::string q = "'";
  q += p.string();
  q += '\'';
  return q;
}

// The Tendril CLI with arguments.
inline CommandResult runTendril(const std::string& args, const std::filesystem::path& scratch) {
  return runCommand(quoted(cliPath()) + " " + args, scratch);
}

// Runs the Khronos glTF validator (tools/validate-gltf.js, installed by scripts/setup).
inline CommandResult validateGltf(const std::filesystem::path& file, const std::filesystem::path& scratch) {
  return runCommand("node " + quoted(sourceDir() / "tools" / "validate-gltf.js") + " " + quoted(file), scratch);
}

}  // namespace tendril::test
