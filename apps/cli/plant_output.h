// Writing a session's plants as the CLI commands do (grow, edit): output formats, the output
// directory and the .glb/.obj files, and a rendered preview picture.
#pragma once

#include "tendril/io/export_scene.h"
#include "tendril/session/session.h"

#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace tendril::cli {

// "glb,obj" → {"glb", "obj"}; anything else is an Error naming --format.
std::set<std::string> parseFormats(const std::string& list);
// Creates the directory if missing; an Error naming -o if it cannot be.
std::filesystem::path prepareOutputDir(const std::string& dir);

// Meshes the session's plants (and the obstacles, if the scene asks) and writes
// <outDir>/<stem>.glb and/or .obj. `source` names the input in validation errors. The
// snapshot written is kept in `written` (for animation export); returns the files written.
std::vector<std::string> writePlantFiles(const session::Session& session, const std::filesystem::path& outDir,
                                         const std::string& stem, const std::set<std::string>& formats,
                                         const std::string& source, io::ExportScene& written);

// Renders the session from the default 3/4 view (headless OpenGL) to a PNG, atomically.
void writePreview(const session::Session& session, const std::filesystem::path& png, int width = 960,
                  int height = 540);

}  // namespace tendril::cli
