#include "plant_output.h"

#include "tendril/core/error.h"

#include <fmt/format.h>

namespace tendril::cli {

std::set<std::string> parseFormats(const std::string& list) {
  std::set<std::string> out;
  size_t start = 0;
  while (start <= list.size()) {
    size_t comma = list.find(',', start);
    std::string f = list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (f != "glb" && f != "obj")
      throw Error("command line", "--format", fmt::format("unknown format \"{}\" (expected glb, obj or glb,obj)", f));
    out.insert(f);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::filesystem::path prepareOutputDir(const std::string& dir) {
  std::filesystem::path p(dir);
  std::error_code ec;
  if (std::filesystem::exists(p, ec) && !std::filesystem::is_directory(p, ec))
    throw Error("command line", "-o", fmt::format("{} exists and is not a directory", dir));
  std::filesystem::create_directories(p, ec);
  if (ec) throw Error("command line", "-o", fmt::format("cannot create directory {}: {}", dir, ec.message()));
  return p;
}

}  // namespace tendril::cli
