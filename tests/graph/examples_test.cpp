// Every example graph of examples/graphs (seed 004's models): it reads, expands, builds a valid
// PlantModel, exports a .glb the Khronos validator accepts, and renders a preview image.
#include "graph_test_util.h"
#include "preview.h"
#include "support/determinism.h"
#include "support/gltf_validator.h"
#include "support/test_paths.h"

#include "tendril/io/gltf_writer.h"
#include "tendril/io/image.h"

namespace tendril {
namespace {

namespace fs = std::filesystem;

const char* kExamples[] = {"sunflower", "rhododendron", "chestnut", "agave", "willow", "philodendron", "pine", "pine-deformed", "fig2", "point-sets", "advent-wreath"};

fs::path examplePath(const std::string& name) { return test::sourceDir() / "examples/graphs" / (name + ".json"); }

TEST(GraphExamples, EveryExampleExportsAGlbTheValidatorAccepts) {
  fs::path dir = test::scratchDir();
  for (const char* name : kExamples) {
    SCOPED_TRACE(name);
    auto g = graph::loadGraph(examplePath(name));
    io::ExportScene scene;
    scene.plants.push_back(graph::generatePlant(g, {g->seed, {}}));
    const plant::PlantModel& p = scene.plants[0];
    EXPECT_NO_THROW(plant::validate(p, name));
    EXPECT_GT(p.nodeCount() + p.leafCount() + p.primitives.size(), 0u);
    fs::path file = dir / (std::string(name) + ".glb");
    io::writeGlb(scene, file);
    meshtest::GltfValidation v = meshtest::validateGltf(file);
    EXPECT_EQ(v.exitCode, 0) << v.output;
    EXPECT_EQ(v.errors, 0) << v.output;
  }
}

TEST(GraphExamples, OutputIsBitIdenticalForAnyThreadCount) {
  for (const char* name : kExamples) {
    SCOPED_TRACE(name);
    auto g = graph::loadGraph(examplePath(name));
    const uint64_t one =
        tendril::test::sameAtEveryThreadCount([&] { return plant::contentHash(graph::generatePlant(g, {g->seed, {}})); });
    // Another seed gives another plant wherever the graph uses random numbers.
    if (std::string(name) != "fig2" && std::string(name) != "point-sets") {
      EXPECT_NE(one, plant::contentHash(graph::generatePlant(g, {g->seed + 1, {}})));
    }
  }
}

TEST(GraphExamples, ThePapersModelsShowTheirFeatures) {
  // Fig. 8: the agave's leaves curve more the further they are from the centre (the Phiball's
  // iteration number), with a random offset.
  {
    auto g = graph::loadGraph(examplePath("agave"));
    graph::ITree t = graph::expand(g, {g->seed, {}});
    ASSERT_EQ(t.leaves.size(), 42u);
    double sx = 0, sy = 0, sxx = 0, sxy = 0, residual = 0;
    for (const graph::LeafItem& l : t.leaves) {
      double x = t.instances[size_t(l.instance)].iteration, y = degrees(l.curvature);
      sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    double n = 42.0, slope = (n * sxy - sx * sy) / (n * sxx - sx * sx), icpt = (sy - slope * sx) / n;
    for (const graph::LeafItem& l : t.leaves)
      residual = std::max(residual, std::abs(degrees(l.curvature) - (icpt + slope * t.instances[size_t(l.instance)].iteration)));
    EXPECT_NEAR(slope * 41.0, 45.0, 7.0);  // "6 + 45 t + jitter(8)"
    EXPECT_GT(residual, 2.0);               // the noise is there ...
    EXPECT_LT(residual, 8.5);               // ... and bounded by jitter(8)
  }
  // Fig. 5: the rhododendron's main twigs branch in tiny twigs exactly at iterations 2 and 13.
  {
    auto g = graph::loadGraph(examplePath("rhododendron"));
    graph::ITree t = graph::expand(g, {g->seed, {}});
    size_t mains = t.countOf("main-twig");
    EXPECT_EQ(mains, 20u);
    EXPECT_EQ(t.countOf("twig"), 2 * mains);
    EXPECT_EQ(t.countOf("main-leaf"), 14 * mains);
    for (const graph::Instance* i : graphtest::instancesOf(t, "twig")) EXPECT_TRUE(i->iteration == 2 || i->iteration == 13);
  }
  // Fig. 6: the chestnut is a cascade of four Tree components with leaves on the last.
  {
    auto g = graph::loadGraph(examplePath("chestnut"));
    graph::ITree t = graph::expand(g, {g->seed, {}});
    for (const char* c : {"trunk", "bough", "branch", "twig"})
      EXPECT_EQ(g->components[size_t(g->find(c))].type, graph::ComponentType::Tree) << c;
    EXPECT_EQ(t.countOf("leaflet"), 14u * 10u * 8u * 6u * 7u);
  }
}

TEST(GraphExamples, PreviewImages) {
  fs::path dir = test::scratchDir();
  for (const char* name : kExamples) {
    SCOPED_TRACE(name);
    auto g = graph::loadGraph(examplePath(name));
    plant::PlantModel p = graph::generatePlant(g, {g->seed, {}});
    graphtest::PreviewCamera camera = graphtest::frameBounds(p);
    if (g->camera.given) camera = {g->camera.eye, g->camera.target, g->camera.fov};
    io::writePng(graphtest::renderPreview(p, camera, 640, 640, g->lights.front().direction), dir / (std::string(name) + ".png"));
    io::writePng(graphtest::renderPreview(p, graphtest::frameBounds(p), 640, 640, g->lights.front().direction),
                 dir / (std::string(name) + "-overview.png"));
  }
  // Close-ups of details worth checking by eye.
  struct Detail {
    const char* name;
    graphtest::PreviewCamera camera;
  };
  const Detail kDetails[] = {{"sunflower", {Vec3(0.15f, 1.85f, 0.75f), Vec3(0.0f, 1.8f, 0.05f), 35.0f}},
                             {"pine", {Vec3(1.5f, 3.2f, 3.0f), Vec3(1.2f, 2.6f, 0.0f), 30.0f}},
                             {"agave", {Vec3(0.0f, 2.2f, 0.4f), Vec3(0.0f, 0.2f, 0.0f), 40.0f}}};
  for (const Detail& d : kDetails) {
    auto g = graph::loadGraph(examplePath(d.name));
    plant::PlantModel p = graph::generatePlant(g, {g->seed, {}});
    io::writePng(graphtest::renderPreview(p, d.camera, 640, 640, g->lights.front().direction),
                 dir / (std::string(d.name) + "-detail.png"));
  }
}

}  // namespace
}  // namespace tendril
