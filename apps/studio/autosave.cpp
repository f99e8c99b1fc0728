#include "autosave.h"

#include "tendril/core/error.h"
#include "tendril/session/session_file.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace tendril::studio {

std::filesystem::path defaultAutosavePath() {
  const char* state = std::getenv("XDG_STATE_HOME");
  if (state && *state) return std::filesystem::path(state) / "tendril" / "autosave.tses";
  const char* home = std::getenv("HOME");
  if (home && *home) return std::filesystem::path(home) / ".local" / "state" / "tendril" / "autosave.tses";
  return {};
}

Autosave::Autosave(AutosaveSettings settings) : settings_(std::move(settings)) {
  if (settings_.path.empty()) return;
  std::error_code ec;
  const std::filesystem::path dir = settings_.path.parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  if (ec) {
    message_ = fmt::format("no autosave: cannot create {}: {}", dir.string(), ec.message());
    return;
  }
  const std::string lockPath = settings_.path.string() + ".lock";
  const int fd = ::open(lockPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) {
    message_ = fmt::format("no autosave: cannot open {}: {}", lockPath, std::strerror(errno));
    return;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    message_ = fmt::format("no autosave: {} is in use by another tendril-studio", settings_.path.string());
    return;
  }
  lock_ = fd;
  struct stat st;
  if (::stat(settings_.path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) {
    leftover_ = true;
    std::tm local{};
    const std::time_t when = st.st_mtime;
    ::localtime_r(&when, &local);
    char text[64];
    std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S", &local);
    leftoverTime_ = text;
  }
}

Autosave::~Autosave() {
  if (lock_ >= 0) ::close(lock_);  // releases the lock; the lock file stays (removing it races)
}

void Autosave::discard() {
  if (!enabled() || !leftover_) return;
  leftover_ = false;
  std::error_code ec;
  std::filesystem::remove(settings_.path, ec);
}

void Autosave::reset(const session::Editor& editor) {
  journalSeen_ = editor.journal().size();
  edits_ = 0;
  steps_ = editor.stepsRun();
  last_ = std::chrono::steady_clock::now();
}

bool Autosave::update(const session::Session& session, const session::Editor& editor) {
  if (!enabled() || leftover_) return false;
  const auto& journal = editor.journal();
  if (journalSeen_ > journal.size()) journalSeen_ = 0;
  for (; journalSeen_ < journal.size(); ++journalSeen_)
    if (!std::holds_alternative<session::Step>(journal[journalSeen_].edit)) ++edits_;
  const bool changed = edits_ > 0 || editor.stepsRun() != steps_;
  const double since = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count();
  const bool due = (settings_.edits > 0 && edits_ >= settings_.edits) ||
                   (settings_.intervalSeconds > 0.0 && since >= settings_.intervalSeconds && changed);
  if (!due) return false;
  // Whatever happens, the next attempt waits for the next change and interval.
  edits_ = 0;
  steps_ = editor.stepsRun();
  last_ = std::chrono::steady_clock::now();
  session::saveSession(settings_.path, session, journal);
  return true;
}

void Autosave::finish() {
  if (!enabled() || leftover_) return;
  std::error_code ec;
  std::filesystem::remove(settings_.path, ec);
}

}  // namespace tendril::studio
