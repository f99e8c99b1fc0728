// What a Session's plants are written as, by every entry point (`tendril grow`, `edit`, `lsys`,
// `model` and the studio's export): every plant, and the obstacles when the scene's output asks
// for them, meshed with the scene's output settings (docs/scene-format.md, "output").
#pragma once

#include "tendril/io/export_scene.h"
#include "tendril/scene/scene.h"
#include "tendril/session/session.h"

#include <string>

namespace tendril::session {

// The scene's output settings as export options (radial segments, subdivisions).
io::ExportOptions exportOptions(const scene::OutputSettings& output);

// Snapshots of every plant, in scene order, each checked with plant::validate (an Error names
// `source`), and with output.include_obstacles every obstacle's mesh in world space.
io::ExportScene exportScene(const Session& session, const std::string& source);

}  // namespace tendril::session
