// The CLI's subcommands. Each lives in its own cmd_*.cpp and registers itself; main.cpp turns
// them into CLI11 subcommands and maps errors to exit codes (0 ok, 2 bad input, 1 internal).
#pragma once

#include "tendril/core/math.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace tendril::cli {

// Configures the subcommand's options and returns the function that runs it (exit code).
using CommandSetup = std::function<std::function<int()>(CLI::App& sub)>;

struct CommandDef {
  std::string name;
  std::string description;
  int order = 0;  // position in --help
  CommandDef* self = nullptr;
  CommandSetup setup;
};

std::vector<CommandDef>& commandRegistry();

struct RegisterCommand {
  RegisterCommand(std::string name, std::string description, int order, CommandSetup setup) {
    commandRegistry().push_back({std::move(name), std::move(description), order, nullptr, std::move(setup)});
  }
};

// Options several commands share.
struct CommonOptions {
  int threads = 0;
  bool quiet = false;
  int64_t maxMeshTriangles = -1;  // < 0: env::MeshImportLimits' default
};
void addCommonOptions(CLI::App& sub, CommonOptions& options);
// Applies --threads, --quiet (log level) and --max-mesh-triangles.
void applyCommonOptions(const CommonOptions& options);
// "x,y,z" → Vec3; anything else is an Error naming the option.
Vec3 parseVec3(const std::string& text, const char* option);

}  // namespace tendril::cli
