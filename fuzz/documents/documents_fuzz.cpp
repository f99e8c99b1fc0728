// libFuzzer target for the JSON documents users write by hand: scenes (docs/scene-format.md),
// component graphs (docs/graph-format.md) and edit scripts (docs/edit-scripts.md). Any bytes are
// parsed as JSON and then read as each of the three. A scene that reads is turned into a session
// (environment, obstacles, seeded plants) and stepped twice; a graph that reads is expanded
// and built into a plant, which must be valid. Every problem in the input must be a
// tendril::Error — anything else (a crash, a hang, a leak, a sanitizer report, another
// exception, an invalid plant) is a bug. Run with `make fuzz`.
//
// The work an input may ask for is what a user may ask for, so a document that legitimately
// asks for a lot (a million air particles, a hundred-metre SDF) is slow here: such inputs are
// cut short by the size caps below rather than reported as hangs.
#include "../fuzz_init.h"
#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"
#include "tendril/graph/build_plant.h"
#include "tendril/graph/graph.h"
#include "tendril/plant/plant_model.h"
#include "tendril/scene/scene.h"
#include "tendril/session/edit_script.h"
#include "tendril/session/session.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace {

using namespace tendril;

// Where relative paths in the documents resolve: nothing is there, so every file they name is
// missing (an Error), and no input reads files outside the fuzzer's control.
const char* const kBaseDir = "/nonexistent/tendril-fuzz";

[[noreturn]] void bug(const char* what, const char* detail) {
  std::fprintf(stderr, "%s: %s\n", what, detail);
  std::abort();
}

// Samples of the signed-distance grids the scene's obstacles would build (as
// Environment::buildSdf sizes them, before its 16M cap).
double sdfSamples(const scene::Scene& scene) {
  double total = 0.0;
  for (const env::ObstacleDef& o : scene.obstacles) {
    const Vec3 size = o.mesh.bounds().size();
    const float cell = o.sdfCell > 0.0f ? o.sdfCell : std::clamp(size.maxCoeff() / 64.0f, 0.01f, 0.05f);
    const Vec3 n = (size / cell).array() + 9.0f;
    total += double(n.x()) * n.y() * n.z();
  }
  return total;
}

void readScene(const Json& json) {
  scene::Scene scene;
  try {
    scene = scene::parseScene(json, "fuzz.json", kBaseDir);
  } catch (const Error&) {
    return;
  }
  // Documents that ask for very large simulations are legitimate but slow: keep to small ones
  // (a larger air fills or emits up to the cap, then stops or fails as it would for a user).
  // (An obstacle's grid of a million samples takes seconds with the sanitizers.)
  if (scene.plants.size() > 8 || scene.steps > 100000 || !(sdfSamples(scene) <= 1e6)) return;
  scene.sph.maxParticles = std::min<size_t>(scene.sph.maxParticles, 20000);
  try {
    session::Session session(std::move(scene));
    session.step();
    session.step();
  } catch (const Error&) {
  }
}

void readGraph(const Json& json) {
  plant::PlantModel plant;
  try {
    std::shared_ptr<const graph::Graph> g = graph::parseGraph(json, "fuzz.json", kBaseDir);
    if (g->maxInstances > 20000) return;  // legitimately large plants: slow, not wrong
    plant = graph::generatePlant(g);
  } catch (const Error&) {
    return;
  }
  try {
    plant::validate(plant, "fuzz.json");
  } catch (const Error& e) {
    bug("the graph built an invalid plant", e.what());
  }
}

void readEditScript(const Json& json) {
  try {
    (void)session::parseEditScript(json, "fuzz.json");
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  Json json;
  try {
    json = parseJson(text, "fuzz.json");
  } catch (const Error&) {
    return 0;
  }
  try {
    readScene(json);
    readGraph(json);
    readEditScript(json);
  } catch (const Error& e) {
    bug("an Error escaped its reader's check", e.what());
  } catch (const std::exception& e) {
    bug("an exception other than tendril::Error", e.what());
  }
  return 0;
}
