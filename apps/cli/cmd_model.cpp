// tendril model GRAPH -o OUT.glb: expands a component graph (seed 004, docs/graph-format.md)
// and writes the plant as .glb or .obj (by the output's extension). It grows a one-plant scene
// (scene/one_plant_scene.h) through a Session, so a scene holding the same plant gives the same
// one.
#include "commands.h"
#include "plant_output.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/timer.h"
#include "tendril/graph/graph.h"
#include "tendril/graph/graph_model.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"
#include "tendril/io/skeleton_writer.h"
#include "tendril/scene/one_plant_scene.h"
#include "tendril/session/plant_export.h"
#include "tendril/session/session.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>

namespace tendril::cli {
namespace {

struct ModelOptions {
  std::string graph;
  std::string output;
  int64_t seed = -1;
  std::vector<std::string> overrides;
  int radialSegments = 8;
  int subdivisions = 3;
  std::string formats;  // empty: the output's extension
  LodOptions lod;
  CommonOptions common;
};

int runModel(const ModelOptions& o) {
  applyCommonOptions(o.common);
  std::filesystem::path out(o.output);
  std::string ext = out.extension().string();
  if (ext != ".glb" && ext != ".obj")
    throw Error("command line", "-o", fmt::format("the output must end in .glb or .obj, got \"{}\"", o.output));
  io::checkOutputPath(out);
  // --format writes each format beside the output, named after its stem.
  const std::set<std::string> formats = o.formats.empty() ? std::set<std::string>{ext.substr(1)} : parseFormats(o.formats);
  const std::filesystem::path outDir = out.parent_path().empty() ? std::filesystem::path(".") : out.parent_path();
  auto file = [&](const char* extension) { return outDir / (out.stem().string() + extension); };
  std::vector<std::string> written;
  std::vector<graph::Override> overrides;
  for (const std::string& s : o.overrides) overrides.push_back(graph::parseOverride(s, "command line", "--set"));

  Timer total;
  std::shared_ptr<const graph::Graph> g = graph::loadGraph(o.graph, overrides);
  // The one-plant scene: the graph at the origin, generated with --seed (default: the graph's
  // "seed"), written with --radial-segments and --subdivisions as the scene's output settings.
  // A scene file holding this plant gives the same plant.
  models::PlantSpec plant;
  plant.name = g->name;
  plant.seed = o.seed >= 0 ? uint64_t(o.seed) : g->seed;
  Timer phase;
  scene::Scene sc = scene::onePlantScene(graph::graphPlant(std::move(plant), g), 0);
  sc.output.radialSegments = o.radialSegments;
  sc.output.subdivisions = o.subdivisions;
  applyLodOptions(o.lod, sc.output);
  session::Session session(std::move(sc));
  double generateSeconds = phase.seconds();
  phase.reset();
  io::ExportScene scene = session::exportScene(session, g->source);
  // Meshed once: the triangle count is reported, and both writers take the meshes.
  io::ExportModel model = io::buildExportModel(scene, session::exportOptions(session.scene().output));
  if (formats.count("glb")) {
    // Pivot Painter textures (output.pivot_painter) beside the .glb, whose TEXCOORD_1 indexes them.
    std::vector<std::string> textures =
        session::writePivotPainterFiles(session, scene, session.scene().output, outDir, out.stem().string(), g->source);
    io::writeGlb(model, file(".glb"), &scene.wind, &scene.pivotPainter);
    written.push_back(file(".glb").string());
    written.insert(written.end(), textures.begin(), textures.end());
  }
  if (formats.count("obj")) {
    io::writeObj(model, file(".obj"));
    written.push_back(file(".obj").string());
  }
  if (formats.count("skeleton")) {
    io::writeSkeleton(scene.plants, file(".skeleton.json"));
    written.push_back(file(".skeleton.json").string());
  }
  double exportSeconds = phase.seconds();

  if (!o.common.quiet) {
    const plant::PlantModel& p = scene.plants[0];
    size_t triangles = 0;
    for (const mesh::PlantMesh& m : model.plantMeshes) triangles += m.triangleCount();
    log::info("{}: {} instances, {} skeleton segments, {} leaves, {} primitives, {} triangles", g->name,
              session.plantSpec(0).paramsAs<graph::GraphPlantParams>()->instances, p.nodeCount(), p.leafCount(), p.primitives.size(), triangles);
    log::info("expand + geometry {:.3f} s, mesh + export {:.3f} s (total {:.3f} s); wrote {}", generateSeconds,
              exportSeconds, total.seconds(), fmt::join(written, ", "));
  }
  return 0;
}

RegisterCommand registerModel("model", "Build a plant from a component graph (Xfrog p-graph) and write .glb or .obj", 15,
                              [](CLI::App& sub) -> std::function<int()> {
  auto o = std::make_shared<ModelOptions>();
  sub.add_option("graph", o->graph, "Graph file (JSON, see docs/graph-format.md)")->required();
  sub.add_option("-o,--output", o->output, "Output file: .glb or .obj (replaced atomically)")->required();
  sub.add_option("--seed", o->seed, "Random seed, as a scene plant's \"seed\" (overrides the graph's \"seed\")")
      ->check(CLI::Range(int64_t(0), int64_t(1) << 53));
  sub.add_option("--set", o->overrides,
                 "Parameter override component/parameter=value (JSON value, else an expression); repeatable");
  sub.add_option("--radial-segments", o->radialSegments, "Vertices around each stem")
      ->check(CLI::Range(3, 64))
      ->capture_default_str();
  sub.add_option("--subdivisions", o->subdivisions, "Spline samples per stem segment")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  sub.add_option("--format", o->formats,
                 "Comma-separated formats to write beside OUT, named after its stem: glb, obj, skeleton "
                 "(default: OUT's extension)");
  addLodOptions(sub, o->lod);
  addCommonOptions(sub, o->common);
  return [o] { return runModel(*o); };
});

}  // namespace
}  // namespace tendril::cli
