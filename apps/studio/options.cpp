#include "options.h"

#include "tendril/core/error.h"

#include <fmt/format.h>

#include <charconv>
#include <filesystem>

namespace tendril::studio {
namespace {

int64_t parseInteger(const std::string& text, const std::string& option, int64_t lo, int64_t hi) {
  int64_t value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || value < lo || value > hi)
    throw Error("command line", option, fmt::format("expected an integer in [{}, {}] (got \"{}\")", lo, hi, text));
  return value;
}

double parseSeconds(const std::string& text, const std::string& option, double hi) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !(value >= 0.0 && value <= hi))
    throw Error("command line", option, fmt::format("expected seconds in [0, {}] (got \"{}\")", hi, text));
  return value;
}

void parseSize(const std::string& text, StudioOptions& o) {
  size_t x = text.find('x');
  if (x == std::string::npos)
    throw Error("command line", "--size", fmt::format("expected WIDTHxHEIGHT such as 1600x900 (got \"{}\")", text));
  o.width = int(parseInteger(text.substr(0, x), "--size", 320, 8192));
  o.height = int(parseInteger(text.substr(x + 1), "--size", 240, 8192));
}

}  // namespace

StudioOptions parseOptions(const std::vector<std::string>& args) {
  StudioOptions o;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw Error("command line", a, "needs a value");
      return args[++i];
    };
    if (a == "-h" || a == "--help") {
      o.help = true;
    } else if (a == "--script") {
      o.script = value();
    } else if (a == "--frames") {
      o.frames = parseInteger(value(), a, 0, 10000000);
    } else if (a == "--screenshot") {
      o.screenshot = value();
    } else if (a == "--save-session") {
      o.saveSession = value();
    } else if (a == "--export") {
      o.exportPath = value();
      std::string ext = std::filesystem::path(o.exportPath).extension().string();
      if (ext != ".glb" && ext != ".obj")
        throw Error("command line", a, fmt::format("expected a .glb or .obj file (got \"{}\")", o.exportPath));
    } else if (a == "--size") {
      parseSize(value(), o);
    } else if (a == "--select") {
      o.select = value();
      size_t colon = o.select.find(':');
      const std::string kind = o.select.substr(0, colon);
      if (colon == std::string::npos ||
          (kind != "plant" && kind != "obstacle" && kind != "light" && kind != "emitter" && kind != "stroke"))
        throw Error("command line", a,
                    fmt::format("expected KIND:INDEX with KIND plant, obstacle, light, emitter or stroke (got \"{}\")",
                                o.select));
      parseInteger(o.select.substr(colon + 1), a, 0, 1000000);
    } else if (a == "--speed") {
      o.speed = int(parseInteger(value(), a, 1, 1000));
    } else if (a == "--stats") {
      o.stats = true;
    } else if (a == "--paused") {
      o.paused = true;
    } else if (a == "--no-sway") {
      o.sway = false;
    } else if (a == "--autosave") {
      o.autosave = value();
      if (o.autosave.empty()) throw Error("command line", a, "expected a file name or \"off\"");
    } else if (a == "--autosave-interval") {
      o.autosaveInterval = parseSeconds(value(), a, 86400.0);
    } else if (a == "--autosave-edits") {
      o.autosaveEdits = int(parseInteger(value(), a, 0, 1000000));
    } else if (a == "--restore-autosave") {
      o.restoreAutosave = value();
      if (o.restoreAutosave != "ask" && o.restoreAutosave != "yes" && o.restoreAutosave != "no")
        throw Error("command line", a, fmt::format("expected ask, yes or no (got \"{}\")", o.restoreAutosave));
    } else if (!a.empty() && a[0] == '-') {
      throw Error("command line", a, "unknown option (see tendril-studio --help)");
    } else if (o.input.empty()) {
      o.input = a;
    } else {
      throw Error("command line", a, fmt::format("only one scene or session file may be given (already have \"{}\")", o.input));
    }
  }
  if (o.help) return o;
  if (o.frames >= 0 && o.screenshot.empty())
    throw Error("command line", "--screenshot", "--frames needs --screenshot OUT.png (the headless run writes it)");
  if (!o.screenshot.empty() && o.frames < 0)
    throw Error("command line", "--frames", "--screenshot needs --frames N (how many frames to run first)");
  if (!o.exportPath.empty() && o.frames < 0)
    throw Error("command line", "--export", "--export needs --frames N (headless runs export when done)");
  if (!o.saveSession.empty() && o.frames < 0)
    throw Error("command line", "--save-session", "--save-session needs --frames N (headless runs save when done)");
  if (!o.screenshot.empty() && (o.screenshot.size() < 4 || o.screenshot.substr(o.screenshot.size() - 4) != ".png"))
    throw Error("command line", "--screenshot", fmt::format("expected a .png file (got \"{}\")", o.screenshot));
  return o;
}

std::string usage() {
  return "usage: tendril-studio [SCENE|SESSION] [options]\n"
         "  SCENE|SESSION          a scene (.json, see docs/scene-format.md) or a saved session; default: "
         "examples/scenes/default.json\n"
         "  --script EDITS.json    replay an edit script (timed edit commands) as the timeline plays\n"
         "  --frames N             headless: run N frames, write --screenshot and exit\n"
         "  --screenshot OUT.png   headless: the whole window, UI included, after the last frame\n"
         "  --save-session F.tses headless: also save the session after the last frame\n"
         "  --export OUT.glb|.obj  headless: also export the plants after the last frame\n"
         "  --size WxH             window size in pixels (default 1600x900)\n"
         "  --speed K              growth steps per frame while playing (default 1)\n"
         "  --paused               start with the timeline paused (interactive runs; headless runs too)\n"
         "  --no-sway              start with the plants still in the wind (the wind panel's \"sway\")\n"
         "  --select KIND:INDEX    select plant:N, obstacle:N, light:N, emitter:N or stroke:N at the start\n"
         "  --stats                print per-frame timing: simulation, scene update, GL draw\n"
         "  --autosave FILE|off    autosave file (default $XDG_STATE_HOME/tendril/autosave.tses, else\n"
         "                         ~/.local/state/tendril/autosave.tses; headless runs: none unless given)\n"
         "  --autosave-interval S  autosave a changed session every S seconds (default 60; 0 = never)\n"
         "  --autosave-edits K     ... and after every K edits (default 20; 0 = never)\n"
         "  --restore-autosave ask|yes|no  an autosave left by a session that did not exit cleanly: ask\n"
         "                         (default), restore it or discard it\n"
         "  -h, --help             this text\n";
}

}  // namespace tendril::studio
