// What a Session's plants are written as, by every entry point (`tendril grow`, `edit`, `lsys`,
// `model` and the studio's export): every plant, and the obstacles when the scene's output asks
// for them, meshed with the scene's output settings (docs/scene-format.md, "output").
#pragma once

#include "tendril/io/export_scene.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"
#include "tendril/wind/gltf_animation.h"

#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace tendril::session {

// The scene's output settings as export options (radial segments, subdivisions, levels of
// detail).
io::ExportOptions exportOptions(const scene::OutputSettings& output);

// Snapshots of every plant, in scene order, each checked with plant::validate (an Error names
// `source`), with output.include_obstacles every obstacle's mesh in world space, and with
// output.wind_data every plant's engine wind table (wind/engine_wind.h, docs/engine-wind.md).
io::ExportScene exportScene(const Session& session, const std::string& source);

// Meshes the session's plants (and the obstacles, if the scene asks) and writes
// <outDir>/<stem>.glb and/or .obj, and the plant graph as <outDir>/<stem>.skeleton.json
// (io/skeleton_writer.h): `formats` holds "glb", "obj", "skeleton". Each file is written
// atomically. `source` names the input in validation errors. The snapshot written is kept in
// `written` (for animation export); returns the files written. What `tendril grow`, `tendril
// edit`, `lsys`, `model` and the Python module's Session.export write. `output`, if given,
// replaces the scene's output settings (the CLI's --lods, --lod-ratio); with levels of detail
// the .obj's lower levels are <stem>_LOD1.obj, ... (listed in the files written).
std::vector<std::string> writePlantFiles(const Session& session, const std::filesystem::path& outDir,
                                         const std::string& stem, const std::set<std::string>& formats,
                                         const std::string& source, io::ExportScene& written,
                                         const scene::OutputSettings* output = nullptr);

// With the output's pivot_painter (io/pivot_painter.h): per plant of `exported` its Pivot
// Painter grid in exported.pivotPainter (what the .glb writer gives TEXCOORD_1 by), and its two
// textures written beside <outDir>/<stem>.glb, each atomically, from the plants' engine wind
// tables (exported.wind, or made here when the output has no wind_data). Returns the files
// written (none without the option). An Error naming `source` with output.instancing, or for a
// plant with more nodes than the textures hold.
std::vector<std::string> writePivotPainterFiles(const Session& session, io::ExportScene& exported,
                                                const scene::OutputSettings& output, const std::filesystem::path& outDir,
                                                const std::string& stem, const std::string& source);

// The exported plants with their Growth-Flow constants, for the wind and growth clips. A node
// of a plant that is not a support clings to a support plant's stem when that stem's surface is
// the nearest within kClingReach (Session::attachments): the clip moves it with its host.
// `exported` holds the session's plants as plants() gives them, in its order.
inline constexpr float kClingReach = 0.08f;  // m: the climbing species' adhesion distance
std::vector<wind::AnimatedPlant> animatedPlants(const Session& session, const io::ExportScene& exported);
// A wind clip of `seconds` with the scene's output settings (fps, joints, mesh) and seed.
wind::WindAnimationOptions windClipOptions(const Session& session, float seconds);

}  // namespace tendril::session
