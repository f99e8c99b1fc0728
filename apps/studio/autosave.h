// The studio's autosave: the session is written now and then (session::saveSession, so
// atomically) to one file, which a clean exit removes. An autosave found at startup is thus
// from a session that crashed or was killed, and the studio offers to restore it. While a
// studio runs it holds a lock (flock) on `<file>.lock` beside it: a second studio started with
// the same file sees the lock, leaves the file alone and does not autosave. The kernel drops
// the lock of a process that dies, so a crash leaves none.
#pragma once

#include "tendril/session/edit.h"
#include "tendril/session/session.h"

#include <chrono>
#include <filesystem>
#include <string>

namespace tendril::studio {

struct AutosaveSettings {
  std::filesystem::path path;     // empty: no autosave
  double intervalSeconds = 60.0;  // wall time between autosaves of a changed session (0 = none)
  int edits = 20;                 // an autosave after this many edits (0 = none)
};

// `$XDG_STATE_HOME/tendril/autosave.tses`, else `$HOME/.local/state/tendril/autosave.tses`;
// empty when neither variable is set.
std::filesystem::path defaultAutosavePath();

class Autosave {
 public:
  // Creates the file's directory and takes the lock; on failure (or another studio's lock) the
  // autosave is off and message() says why.
  explicit Autosave(AutosaveSettings settings);
  ~Autosave();
  Autosave(const Autosave&) = delete;
  Autosave& operator=(const Autosave&) = delete;

  bool enabled() const { return lock_ >= 0; }
  const std::filesystem::path& path() const { return settings_.path; }
  // Why the autosave is off, or empty.
  const std::string& message() const { return message_; }

  // An autosave a session that did not exit cleanly left (seen when the lock was taken), and
  // when it was written (local time, "2024-06-01 14:03:27").
  bool leftover() const { return leftover_; }
  const std::string& leftoverTime() const { return leftoverTime_; }
  // The question is answered: the leftover is restored (it stays until the next autosave
  // replaces it, in case the studio dies again first) or discarded (removed).
  void restored() { leftover_ = false; }
  void discard();

  // The editor's state now counts as saved (after opening a file).
  void reset(const session::Editor& editor);
  // Once a frame: writes the session when it changed and an autosave is due (enough edits, or
  // the interval passed). Returns true when it wrote; throws the Error of a failed write (the
  // next attempt then waits for the next change and interval).
  bool update(const session::Session& session, const session::Editor& editor);
  // A clean exit: removes the autosave (not while a leftover's question is unanswered).
  void finish();

 private:
  AutosaveSettings settings_;
  int lock_ = -1;
  std::string message_;
  bool leftover_ = false;
  std::string leftoverTime_;
  size_t journalSeen_ = 0;  // journal entries counted so far
  int edits_ = 0;           // edits (not steps) since the last autosave
  uint32_t steps_ = 0;      // the editor's clock at the last autosave
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace tendril::studio
