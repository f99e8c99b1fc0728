// libFuzzer target for session files (.tses, docs/session-format.md): a binary archive of the
// scene document and the full state of every plant, the simulated air and the journal. Any
// bytes are written to a file and loaded. Damaged contents must be a tendril::Error naming the
// file; a session that loads is stepped once, saved and loaded again, which must succeed —
// anything else (a crash, a hang, a leak, a sanitizer report, another exception) is a bug.
// Run with `make fuzz`; the seed corpus is written by `fuzz/session/make-corpus.sh`.
#include "../fuzz_init.h"
#include "tendril/core/error.h"
#include "tendril/session/session.h"
#include "tendril/session/session_file.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

[[noreturn]] void bug(const char* what, const char* detail) {
  std::fprintf(stderr, "%s: %s\n", what, detail);
  std::abort();
}

std::filesystem::path scratch(const char* name) {
  static const std::filesystem::path dir = [] {
    std::filesystem::path d = std::filesystem::temp_directory_path() / ("tendril-session-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir / name;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace tendril;
  const std::filesystem::path input = scratch("input.tses"), again = scratch("again.tses");
  {
    std::ofstream out(input, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  session::LoadedSession loaded;
  try {
    loaded = session::loadSession(input);
  } catch (const Error& e) {
    if (std::string(e.what()).find(input.string()) == std::string::npos) bug("the error does not name the file", e.what());
    return 0;
  } catch (const std::exception& e) {
    bug("an exception other than tendril::Error", e.what());
  }
  try {
    loaded.session->step();
  } catch (const Error&) {
    return 0;  // e.g. a scene whose mesh obstacle file is missing here
  } catch (const std::exception& e) {
    bug("stepping a loaded session threw", e.what());
  }
  try {
    session::saveSession(again, *loaded.session, loaded.journal);
    (void)session::loadSession(again);
  } catch (const std::exception& e) {
    bug("a loaded session did not save and load again", e.what());
  }
  return 0;
}
