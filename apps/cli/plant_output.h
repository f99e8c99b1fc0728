// Writing a session's plants as the CLI commands do (grow, edit): output formats and the output
// directory.
#pragma once

#include "tendril/io/export_scene.h"
#include "tendril/render/session_render.h"
#include "tendril/session/plant_export.h"
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

// Shared with the Python module: session::writePlantFiles (session/plant_export.h) and
// render::writePreview (render/session_render.h).
using session::writePlantFiles;
using render::writePreview;

}  // namespace tendril::cli
