// Test helpers for exporters: a fresh output directory per test and the Khronos glTF
// validator (tools/validate-gltf.js run with node).
#pragma once

#include <filesystem>
#include <string>

namespace tendril::meshtest {

// <build>/test-tmp/<Suite>.<Test>, emptied.
std::filesystem::path exportTestDir();

struct GltfValidation {
  int exitCode = -1;
  int errors = -1;    // -1 when the validator's summary line was not found
  int warnings = -1;
  std::string output;  // everything the validator printed
};

// Runs `node tools/validate-gltf.js FILE` and parses its "FILE: errors=N warnings=N" line.
// A missing node or validator shows as exitCode != 0 and errors = -1, which tests must treat
// as a failure.
GltfValidation validateGltf(const std::filesystem::path& file);

}  // namespace tendril::meshtest
