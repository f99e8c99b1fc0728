// tendril-studio's command line: an optional scene or session file, and the headless mode
// (`--script EDITS.json --frames N --screenshot OUT.png`) that replays edits, renders the full
// window and exits.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace tendril::studio {

struct StudioOptions {
  std::string input;       // scene (.json) or session file; empty = the default scene
  std::string script;      // edit script replayed on the timeline; empty = none
  int64_t frames = -1;     // headless: frames to run before the screenshot (-1 = interactive)
  std::string screenshot;  // headless: PNG written after the last frame
  std::string saveSession; // headless: session file written after the last frame
  std::string exportPath;  // headless: plants exported (.glb or .obj) after the last frame
  int width = 1600;        // window size (pixels)
  int height = 900;
  std::string select;      // "plant:0", "obstacle:1", ...: selected at the start (screenshots)
  int speed = 1;           // growth steps per frame while playing
  bool stats = false;      // per-frame timing on stdout
  bool paused = false;     // start paused (headless runs too: the frames then only move in the wind)
  bool sway = true;        // plants move in the scene's wind (the wind panel's toggle)
  // The autosave (autosave.h): its file ("off": none; empty: the default file for interactive
  // runs, none for headless ones), how often, and the answer to restoring one a session that
  // did not exit cleanly left ("ask": the dialog; headless runs answer with "yes" or "no").
  std::string autosave;
  double autosaveInterval = 60.0;  // seconds of wall time (0 = no timed autosaves)
  int autosaveEdits = 20;          // edits (0 = no autosaves counted in edits)
  std::string restoreAutosave = "ask";
  bool help = false;

  bool headless() const { return frames >= 0; }
};

// Throws Error("command line", "<argument>", what was expected) for an unknown option, a
// missing or malformed value, or a headless run without both --frames and --screenshot.
StudioOptions parseOptions(const std::vector<std::string>& args);

// The usage text printed by --help.
std::string usage();

}  // namespace tendril::studio
