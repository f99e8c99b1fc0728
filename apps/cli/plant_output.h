// Writing a session's plants as the CLI commands do (grow, edit): output formats and the output
// directory.
#pragma once

#include "tendril/io/export_scene.h"
#include "tendril/render/session_render.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace tendril::cli {

// "glb,obj,skeleton" → {"glb", "obj", "skeleton"} (any of them, comma-separated); anything else
// is an Error naming --format.
std::set<std::string> parseFormats(const std::string& list);
// Creates the directory if missing; an Error naming -o if it cannot be.
std::filesystem::path prepareOutputDir(const std::string& dir);

// --lods N and --lod-ratio R (grow, edit, lsys, model): levels of detail per plant, overriding
// the scene's output.lods / lod_ratio; either one replaces output.lod_triangles by the ratio's
// budgets. 0 = not given. With them, --leaf-atlas: each plant's leaf textures packed into one
// atlas (sets the scene's output.leaf_atlas).
struct LodOptions {
  int lods = 0;
  double ratio = 0.0;
  bool leafAtlas = false;
  bool windData = false;  // --wind-data: engine wind data in the .glb (sets output.wind_data)
  bool impostor = false;  // --impostor: a billboard impostor as the last level (sets output.impostor)
  bool instancing = false;  // --instancing: GPU instancing of repeated primitives (sets output.instancing)
  bool maps = false;        // --maps: bark normal/roughness and leaf normal maps (sets output.maps)
  bool pivotPainter = false;  // --pivot-painter: Pivot Painter 2 textures (sets output.pivot_painter)
};
void addLodOptions(CLI::App& sub, LodOptions& options);
// Applies the options to `output`; --lod-ratio without levels of detail (from --lods or the
// scene) is an Error naming it.
void applyLodOptions(const LodOptions& options, scene::OutputSettings& output);

// Shared with the Python module: session::writePlantFiles (session/plant_export.h) and
// render::writePreview (render/session_render.h).
using session::writePlantFiles;
using render::writePreview;

}  // namespace tendril::cli
