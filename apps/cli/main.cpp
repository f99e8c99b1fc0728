// tendril: the command-line front end over tendril::session. See docs/cli.md.
#include "commands.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/parallel.h"
#include "tendril/env/mesh_import.h"
#include "tendril/render/impostor_baker.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace tendril::cli {

std::vector<CommandDef>& commandRegistry() {
  static std::vector<CommandDef> commands;
  return commands;
}

void addCommonOptions(CLI::App& sub, CommonOptions& options) {
  sub.add_option("--threads", options.threads, "Worker threads (0 = all cores); results do not depend on it")
      ->check(CLI::Range(0, 1024));
  sub.add_flag("-q,--quiet", options.quiet, "Print nothing but errors");
  sub.add_option("--max-mesh-triangles", options.maxMeshTriangles,
                 "Refuse mesh files (obstacles, imports) with more triangles than this, before reading them where "
                 "their header tells (default 16777216)")
      ->check(CLI::Range(int64_t(1), int64_t(1) << 32));
}

void applyCommonOptions(const CommonOptions& options) {
  setThreadCount(options.threads);
  if (options.quiet) log::setLevel(log::Level::Error);
  if (options.maxMeshTriangles > 0) {
    env::MeshImportLimits limits = env::meshImportLimits();
    limits.maxTriangles = uint64_t(options.maxMeshTriangles);
    env::setMeshImportLimits(limits);
  }
}

// "x,y,z" → Vec3; anything else is an Error naming the option.
Vec3 parseVec3(const std::string& text, const char* option) {
  auto fail = [&]() -> Error {
    return Error("command line", option, fmt::format("expected three comma-separated numbers such as 1.5,2,4 (got \"{}\")", text));
  };
  Vec3 v;
  const char* p = text.data();
  const char* end = text.data() + text.size();
  for (int i = 0; i < 3; ++i) {
    while (p < end && *p == ' ') ++p;
    float x = 0.0f;
    auto [next, ec] = std::from_chars(p, end, x);
    if (ec != std::errc() || !std::isfinite(x)) throw fail();
    v[i] = x;
    p = next;
    while (p < end && *p == ' ') ++p;
    if (i < 2) {
      if (p == end || *p != ',') throw fail();
      ++p;
    }
  }
  if (p != end) throw fail();
  return v;
}

}  // namespace tendril::cli

int main(int argc, char** argv) {
  using namespace tendril;
  CLI::App app{"Tendril: plants that grow, climb, move in the wind and can be edited while they grow.\n"
               "Exit codes: 0 success, 2 bad input (files, parameters, arguments), 1 internal error.",
               "tendril"};
  app.set_version_flag("--version", std::string("tendril ") + TENDRIL_VERSION);
  render::installRendererImpostorBaker();  // --impostor / output.impostor bake with the renderer
  app.require_subcommand(1);
  app.fallthrough(false);

  auto& commands = cli::commandRegistry();
  std::stable_sort(commands.begin(), commands.end(),
                   [](const cli::CommandDef& a, const cli::CommandDef& b) { return a.order < b.order; });
  std::vector<std::pair<CLI::App*, std::function<int()>>> runners;
  for (cli::CommandDef& c : commands) {
    CLI::App* sub = app.add_subcommand(c.name, c.description);
    runners.emplace_back(sub, c.setup(*sub));
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    std::fprintf(stderr, "tendril: error: command line: %s (see tendril --help)\n", what.c_str());
    return 2;
  }

  try {
    for (auto& [sub, run] : runners)
      if (sub->parsed()) return run();
    return 2;
  } catch (const Error& e) {
    std::fprintf(stderr, "tendril: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tendril: internal error: %s\n", e.what());
    return 1;
  }
}
