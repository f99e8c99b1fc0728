#include "support/gltf_validator.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <regex>
#include <sys/wait.h>

namespace tendril::meshtest {

std::filesystem::path exportTestDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path dir = std::filesystem::path(TENDRIL_TEST_TMP) /
                              (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

GltfValidation validateGltf(const std::filesystem::path& file) {
  GltfValidation r;
  std::filesystem::path script = std::filesystem::path(TENDRIL_SOURCE_DIR) / "tools" / "validate-gltf.js";
  std::string command = "node '" + script.string() + "' '" + file.string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) {
    r.output = "cannot run: " + command;
    return r;
  }
  std::array<char, 4096> buf;
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  int status = ::pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::smatch m;
  static const std::regex kSummary(R"(: errors=(\d+) warnings=(\d+))");
  if (std::regex_search(r.output, m, kSummary)) {
    r.errors = std::stoi(m[1].str());
    r.warnings = std::stoi(m[2].str());
  }
  return r;
}

}  // namespace tendril::meshtest
