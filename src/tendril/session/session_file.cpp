#include "tendril/session/session_file.h"

#include "tendril/core/archive.h"
#include "tendril/core/error.h"
#include "tendril/io/atomic_file.h"
#include "tendril/session/edit_script.h"

#include <fmt/format.h>

#include <fstream>
#include <iterator>

namespace tendril::session {

namespace {

constexpr char kMagic[4] = {'T', 'S', 'E', 'S'};

std::vector<uint8_t> readAll(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path.string(), "", "cannot open the session file");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw Error(path.string(), "", "cannot read the session file");
  return bytes;
}

}  // namespace

void saveSession(const std::filesystem::path& path, const Session& session, const std::vector<TimedEdit>& journal) {
  if (session.sceneDocument().is_null())
    throw Error(path.string(), "",
                "this session was made from a scene without its document and cannot be saved (open the scene "
                "from its file)");
  for (size_t i = 0; i < session.plantCount(); ++i)
    if (session.plantDescription(i).is_null())
      throw Error(path.string(), "",
                  fmt::format("plant \"{}\" was added from code without a scene description and cannot be saved",
                              session.plantSpec(i).name));
  io::checkOutputPath(path);
  ArchiveWriter out;
  out.bytes(kMagic, sizeof kMagic);
  out.u32(kSessionFormatVersion);
  out.string(session.scene().source);
  out.string(std::filesystem::absolute(session.baseDir()).lexically_normal().string());
  out.string(session.sceneDocument().dump());
  std::vector<uint8_t> state = session.saveState();
  out.vector(state);
  out.string(editScriptToJson(journal).dump());
  io::writeFileAtomic(path, std::span<const uint8_t>(out.data()));
}

bool isSessionFile(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  char magic[4] = {};
  return f.read(magic, 4) && std::equal(magic, magic + 4, kMagic);
}

LoadedSession loadSession(const std::filesystem::path& path) {
  const std::string source = path.string();
  if (!std::filesystem::exists(path)) throw Error(source, "", "session file does not exist");
  const std::vector<uint8_t> bytes = readAll(path);
  ArchiveReader in(bytes, source);
  char magic[4] = {};
  if (in.remaining() < 4) in.fail(0, "not a Tendril session file (too short)");
  in.bytes(magic, 4);
  if (!std::equal(magic, magic + 4, kMagic)) in.fail(0, "not a Tendril session file (no TSES magic)");
  const uint32_t version = in.u32();
  if (version != kSessionFormatVersion)
    in.fail(4, fmt::format("session file version {} is not supported (this build reads {})", version,
                           kSessionFormatVersion));
  const std::string sceneSource = in.string();
  const std::filesystem::path baseDir = in.string();
  const size_t docAt = in.position();
  const std::string docText = in.string();
  const size_t stateAt = in.position() + 12;  // after the vector's length and record size
  const std::vector<uint8_t> state = in.vector<uint8_t>();
  const size_t journalAt = in.position();
  const std::string journalText = in.string();
  if (!in.atEnd()) in.fail("unexpected data after the session");

  Json doc;
  try {
    doc = parseJson(docText, source);
  } catch (const Error& e) {
    in.fail(docAt, "the stored scene is damaged: " + e.message());
  }
  // The scene is read as it was written; its errors name the session file and the scene's
  // original name.
  scene::Scene scene;
  try {
    scene = scene::parseScene(doc, sceneSource, baseDir);
  } catch (const Error& e) {
    throw Error(source, "", fmt::format("its scene ({}) no longer loads: {}", sceneSource, e.what()));
  }
  if (!sceneSource.empty() && std::filesystem::path(sceneSource).extension() == ".json") scene.path = sceneSource;
  LoadedSession loaded;
  try {
    loaded.session = std::make_unique<Session>(std::move(scene), std::move(doc), baseDir);
  } catch (const Error& e) {
    throw Error(source, "", fmt::format("its scene ({}) no longer loads: {}", sceneSource, e.what()));
  }
  try {
    loaded.session->loadState(state, source);
  } catch (const Error& e) {
    // Offsets inside the state are reported as offsets in the file.
    std::string location = e.location();
    if (location.rfind("byte ", 0) == 0) location = fmt::format("byte {}", stateAt + std::stoull(location.substr(5)));
    throw Error(source, location, e.message());
  }
  Json journal;
  try {
    journal = parseJson(journalText, source);
  } catch (const Error& e) {
    in.fail(journalAt, "the stored edit journal is damaged: " + e.message());
  }
  loaded.journal = parseEditScript(journal, source + " (journal)").edits;
  return loaded;
}

}  // namespace tendril::session
