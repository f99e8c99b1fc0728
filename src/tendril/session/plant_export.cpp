#include "tendril/session/plant_export.h"

#include "tendril/core/error.h"
#include "tendril/core/parallel.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"
#include "tendril/io/pivot_painter.h"
#include "tendril/io/skeleton_writer.h"
#include "tendril/wind/engine_wind.h"

#include <algorithm>

namespace tendril::session {

io::ExportOptions exportOptions(const scene::OutputSettings& output) {
  io::ExportOptions options;
  options.mesh.radialSegments = output.radialSegments;
  options.mesh.subdivisions = output.subdivisions;
  options.lods.levels = output.lods;
  options.lods.ratio = output.lodRatio;
  options.lods.triangles = output.lodTriangles;
  options.leafAtlas = output.leafAtlas;
  options.impostor.enabled = output.impostor;
  options.impostor.slabs = output.impostorSlabs;
  options.impostor.resolution = output.impostorResolution;
  options.instancing = output.instancing;
  options.maps = output.maps;
  return options;
}

io::ExportScene exportScene(const Session& session, const std::string& source) {
  io::ExportScene out;
  out.plants = session.plants();
  for (const plant::PlantModel& p : out.plants) plant::validate(p, source);
  if (session.scene().output.windData) out.wind = wind::engineWindTables(out.plants, session.growthFlow());
  if (session.scene().output.includeObstacles) {
    const env::Environment& env = session.environment();
    for (uint32_t id = 0; id < env.obstacleCount(); ++id) {
      const env::ObstacleInfo& info = env.obstacle(id);
      io::NamedMesh m{info.name, env.obstacleMesh(id), info.color};
      for (Vec3& v : m.mesh.positions) v = info.worldFromLocal.applyPoint(v);
      out.meshes.push_back(std::move(m));
    }
  }
  return out;
}

std::vector<std::string> writePivotPainterFiles(const Session& session, io::ExportScene& exported,
                                                const scene::OutputSettings& output, const std::filesystem::path& outDir,
                                                const std::string& stem, const std::string& source) {
  exported.pivotPainter.clear();
  if (!output.pivotPainter) return {};
  if (output.instancing)
    throw Error(source, "output.pivot_painter",
                "Pivot Painter textures cannot go with GPU instancing (an instanced copy has no vertices to carry its "
                "element's UV): turn output.instancing off");
  const io::WindTables made = exported.wind.empty() ? wind::engineWindTables(exported.plants, session.growthFlow())
                                                    : io::WindTables{};
  const io::WindTables& tables = exported.wind.empty() ? made : exported.wind;
  const size_t n = exported.plants.size();
  std::vector<io::PivotPainterTextures> textures(n);
  // Every plant checked (its node count) before any file is written; the first failure by index.
  std::vector<std::exception_ptr> failed(n);
  parallelFor(0, n, [&](size_t i) {
    try {
      textures[i] = io::pivotPainterTextures(exported.plants[i], tables.at(i), source);
    } catch (...) {
      failed[i] = std::current_exception();
    }
  }, 1);
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
  std::vector<std::string> written;
  exported.pivotPainter.resize(n);
  std::vector<std::string> names;  // file names made safe, one per plant
  for (size_t i = 0; i < n; ++i) {
    exported.pivotPainter[i] = textures[i].grid;
    if (textures[i].grid.width == 0) continue;  // a plant without nodes
    std::string name = exported.plants[i].name;
    // Two names that are the same once made safe for a file name keep their plants apart by index.
    const std::string file = io::pivotPainterPivotPath(outDir, stem, name).filename().string();
    if (std::find(names.begin(), names.end(), file) != names.end()) name += "-" + std::to_string(i);
    names.push_back(io::pivotPainterPivotPath(outDir, stem, name).filename().string());
    const std::filesystem::path exr = io::pivotPainterPivotPath(outDir, stem, name);
    const std::filesystem::path png = io::pivotPainterXAxisPath(outDir, stem, name);
    io::writePivotPainterTextures(textures[i], exr, png);
    written.push_back(exr.string());
    written.push_back(png.string());
  }
  return written;
}

std::vector<std::string> writePlantFiles(const Session& session, const std::filesystem::path& outDir,
                                         const std::string& stem, const std::set<std::string>& formats,
                                         const std::string& source, io::ExportScene& exported,
                                         const scene::OutputSettings* output) {
  const io::ExportOptions options = exportOptions(output ? *output : session.scene().output);
  exported = exportScene(session, source);
  // exportScene follows the session's output; `output` may differ (edit's command-line options).
  if (!(output ? *output : session.scene().output).windData) exported.wind.clear();
  else if (exported.wind.empty()) exported.wind = wind::engineWindTables(exported.plants, session.growthFlow());
  std::vector<std::string> written;
  if (formats.count("skeleton")) {
    io::writeSkeleton(exported.plants, outDir / (stem + ".skeleton.json"));
    written.push_back((outDir / (stem + ".skeleton.json")).string());
  }
  if (!formats.count("glb") && !formats.count("obj")) return written;
  // Pivot Painter textures go with the .glb, whose TEXCOORD_1 indexes them (not with the .obj).
  if (formats.count("glb"))
    for (std::string& f : writePivotPainterFiles(session, exported, output ? *output : session.scene().output, outDir,
                                                 stem, source))
      written.push_back(std::move(f));
  if (!formats.count("obj")) {
    // Alone, the .glb streams plant by plant (gltf_writer.h): less memory, and faster.
    io::writeGlb(exported, outDir / (stem + ".glb"), options);
    written.push_back((outDir / (stem + ".glb")).string());
    return written;
  }
  // Both formats write the meshes of one model.
  io::ExportModel model = io::buildExportModel(exported, options);
  if (formats.count("glb")) {
    io::writeGlb(model, outDir / (stem + ".glb"), &exported.wind, &exported.pivotPainter);
    written.push_back((outDir / (stem + ".glb")).string());
  }
  if (formats.count("obj")) {
    io::writeObj(model, outDir / (stem + ".obj"));
    written.push_back((outDir / (stem + ".obj")).string());
    size_t levels = 1;
    for (const io::ExportObject& object : model.objects) levels = std::max(levels, object.levels());
    for (size_t level = 1; level < levels; ++level)
      written.push_back(io::objLodPath(outDir / (stem + ".obj"), level).string());
  }
  return written;
}

std::vector<wind::AnimatedPlant> animatedPlants(const Session& session, const io::ExportScene& exported) {
  const std::vector<plant::GrowthFlowSpecies> species = session.growthFlow();
  std::vector<wind::AnimatedPlant> animated;
  for (size_t i = 0; i < exported.plants.size(); ++i) {
    wind::AnimatedPlant a{&exported.plants[i], species.at(i)};
    // Nodes clinging to support plants follow them in the clip.
    const std::vector<Session::Attachment> at = session.attachments(i, exported.plants[i], kClingReach);
    if (std::any_of(at.begin(), at.end(), [](const Session::Attachment& x) { return x.plant >= 0; })) {
      a.hostPlant.resize(at.size());
      a.hostNode.resize(at.size());
      for (size_t k = 0; k < at.size(); ++k) a.hostPlant[k] = at[k].plant, a.hostNode[k] = at[k].node;
    }
    animated.push_back(std::move(a));
  }
  return animated;
}

wind::WindAnimationOptions windClipOptions(const Session& session, float seconds) {
  const scene::Scene& sc = session.scene();
  wind::WindAnimationOptions a;
  a.seconds = seconds;
  a.fps = sc.output.animationFps;
  a.maxJoints = sc.output.animationJoints;
  a.seed = sc.seed;
  a.mesh = exportOptions(sc.output).mesh;
  return a;
}

}  // namespace tendril::session
