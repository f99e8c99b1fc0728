// Session files (.tses, docs/session-format.md): everything needed to continue an interactive
// session exactly — the scene document and its directory (the environment is rebuilt from
// them; mesh obstacles are read again from their files), the full state of every plant, the
// simulated air and the environment edits (Session::saveState), and the journal of applied
// edits. Undo snapshots are not written: a loaded session starts with an empty undo history
// and keeps the journal.
//
// Layout: the magic "TSES", a format version (u32), then an archive (core/archive.h). Writes
// go to a temporary file that replaces the target only when complete (io/atomic_file.h).
#pragma once

#include "tendril/session/edit.h"
#include "tendril/session/session.h"

#include <filesystem>
#include <memory>
#include <vector>

namespace tendril::session {

inline constexpr uint32_t kSessionFormatVersion = 1;

struct LoadedSession {
  std::unique_ptr<Session> session;
  std::vector<TimedEdit> journal;
};

// Throws Error when the session has no scene document or a plant added from code.
void saveSession(const std::filesystem::path& path, const Session& session,
                 const std::vector<TimedEdit>& journal = {});
// Throws Error naming the file for a missing file, a wrong magic, an unknown version or
// damaged contents (with the byte offset).
LoadedSession loadSession(const std::filesystem::path& path);
// True when the file starts with the session magic (tells session files from scenes).
bool isSessionFile(const std::filesystem::path& path);

}  // namespace tendril::session
