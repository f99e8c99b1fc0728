#include "plant_output.h"

#include "tendril/core/error.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"
#include "tendril/io/obj_writer.h"
#include "tendril/render/offscreen.h"
#include "tendril/render/session_render.h"
#include "tendril/session/plant_export.h"

#include <fmt/format.h>

namespace tendril::cli {

std::set<std::string> parseFormats(const std::string& list) {
  std::set<std::string> out;
  size_t start = 0;
  while (start <= list.size()) {
    size_t comma = list.find(',', start);
    std::string f = list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (f != "glb" && f != "obj")
      throw Error("command line", "--format", fmt::format("unknown format \"{}\" (expected glb, obj or glb,obj)", f));
    out.insert(f);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::filesystem::path prepareOutputDir(const std::string& dir) {
  std::filesystem::path p(dir);
  std::error_code ec;
  if (std::filesystem::exists(p, ec) && !std::filesystem::is_directory(p, ec))
    throw Error("command line", "-o", fmt::format("{} exists and is not a directory", dir));
  std::filesystem::create_directories(p, ec);
  if (ec) throw Error("command line", "-o", fmt::format("cannot create directory {}: {}", dir, ec.message()));
  return p;
}

std::vector<std::string> writePlantFiles(const session::Session& session, const std::filesystem::path& outDir,
                                         const std::string& stem, const std::set<std::string>& formats,
                                         const std::string& source, io::ExportScene& exportScene) {
  const io::ExportOptions options = session::exportOptions(session.scene().output);
  exportScene = session::exportScene(session, source);
  std::vector<std::string> written;
  if (formats.size() == 1 && formats.count("glb")) {
    // Alone, the .glb streams plant by plant (gltf_writer.h): less memory, and faster.
    io::writeGlb(exportScene, outDir / (stem + ".glb"), options);
    written.push_back((outDir / (stem + ".glb")).string());
    return written;
  }
  // Both formats write the meshes of one model.
  io::ExportModel model = io::buildExportModel(exportScene, options);
  if (formats.count("glb")) {
    io::writeGlb(model, outDir / (stem + ".glb"));
    written.push_back((outDir / (stem + ".glb")).string());
  }
  if (formats.count("obj")) {
    io::writeObj(model, outDir / (stem + ".obj"));
    written.push_back((outDir / (stem + ".obj")).string());
  }
  return written;
}

void writePreview(const session::Session& session, const std::filesystem::path& png, int width, int height) {
  io::checkOutputPath(png);
  render::SessionScene view(session);
  render::RenderSettings settings;
  settings.width = width;
  settings.height = height;
  const render::Camera camera = render::frameBounds(render::focusBounds(view.scene()), render::kDefaultViewDirection,
                                                    float(width) / float(height), radians(40.0f));
  render::OffscreenRenderer renderer;
  io::writeFileAtomic(png, io::encodePng(renderer.render(view.scene(), camera, settings)));
}

}  // namespace tendril::cli
