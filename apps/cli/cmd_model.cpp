// tendril model GRAPH -o OUT.glb: expands a component graph (seed 004, docs/graph-format.md)
// and writes the plant as .glb or .obj (by the output's extension).
#include "commands.h"

#include "tendril/core/error.h"
#include "tendril/core/log.h"
#include "tendril/core/timer.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/expand.h"
#include "tendril/graph/graph.h"
#include "tendril/io/atomic_file.h"
#include "tendril/io/export_model.h"
#include "tendril/io/gltf_writer.h"
#include "tendril/io/obj_writer.h"

#include <fmt/format.h>

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
  CommonOptions common;
};

int runModel(const ModelOptions& o) {
  applyCommonOptions(o.common);
  std::filesystem::path out(o.output);
  std::string ext = out.extension().string();
  if (ext != ".glb" && ext != ".obj")
    throw Error("command line", "-o", fmt::format("the output must end in .glb or .obj, got \"{}\"", o.output));
  io::checkOutputPath(out);
  std::vector<graph::Override> overrides;
  for (const std::string& s : o.overrides) overrides.push_back(graph::parseOverride(s, "command line", "--set"));

  Timer total;
  std::shared_ptr<const graph::Graph> g = graph::loadGraph(o.graph, overrides);
  graph::ExpandOptions options;
  options.seed = o.seed >= 0 ? uint64_t(o.seed) : g->seed;
  Timer phase;
  graph::ITree tree = graph::expand(g, options);
  double expandSeconds = phase.seconds();
  phase.reset();
  io::ExportScene scene;
  scene.plants.push_back(graph::buildPlant(tree));
  double geometrySeconds = phase.seconds();
  phase.reset();
  io::ExportOptions exportOptions;
  exportOptions.mesh.radialSegments = o.radialSegments;
  exportOptions.mesh.subdivisions = o.subdivisions;
  io::ExportModel model = io::buildExportModel(scene, exportOptions);
  if (ext == ".glb")
    io::writeGlb(model, out);
  else
    io::writeObj(model, out);
  double exportSeconds = phase.seconds();

  if (!o.common.quiet) {
    const plant::PlantModel& p = scene.plants[0];
    size_t triangles = 0;
    for (const mesh::PlantMesh& m : model.plantMeshes) triangles += m.triangleCount();
    log::info("{}: {} instances, {} skeleton segments, {} leaves, {} primitives, {} triangles", g->name,
              tree.instances.size(), p.nodeCount(), p.leafCount(), p.primitives.size(), triangles);
    log::info("expand {:.3f} s, geometry {:.3f} s, mesh + export {:.3f} s (total {:.3f} s); wrote {}", expandSeconds,
              geometrySeconds, exportSeconds, total.seconds(), out.string());
  }
  return 0;
}

RegisterCommand registerModel("model", "Build a plant from a component graph (Xfrog p-graph) and write .glb or .obj", 15,
                              [](CLI::App& sub) -> std::function<int()> {
  auto o = std::make_shared<ModelOptions>();
  sub.add_option("graph", o->graph, "Graph file (JSON, see docs/graph-format.md)")->required();
  sub.add_option("-o,--output", o->output, "Output file: .glb or .obj (replaced atomically)")->required();
  sub.add_option("--seed", o->seed, "Random seed (overrides the graph's \"seed\")")->check(CLI::NonNegativeNumber);
  sub.add_option("--set", o->overrides,
                 "Parameter override component/parameter=value (JSON value, else an expression); repeatable");
  sub.add_option("--radial-segments", o->radialSegments, "Vertices around each stem")
      ->check(CLI::Range(3, 64))
      ->capture_default_str();
  sub.add_option("--subdivisions", o->subdivisions, "Spline samples per stem segment")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  addCommonOptions(sub, o->common);
  return [o] { return runModel(*o); };
});

}  // namespace
}  // namespace tendril::cli
