// Interpretation of an L-system string by a 3D turtle (ABOP §1.3, §1.5): the turtle's frame is
// heading H, left L and up U (H × L = U); F draws a segment — one PlantModel node whose local
// +Y is H and local +Z is U (so a climbing grammar that keeps U away from its support follows
// the PlantModel convention) — brackets branch, ~leaf places PlantModel leaves, { . } draws
// polygons, and ABOP §2.4 tropism bends the heading after every segment. Interpretation
// (homomorphism) rules are expanded on the way, up to their maximum depth.
//
// The same walk fills query modules: ?P, ?H, ?U, ?L from the turtle and ?E from the
// Environment (closest surface, ray hit ahead, light, attraction), as in open L-systems (Měch
// and Prusinkiewicz 1996), which is how seed 003's tips query their surroundings.
#pragma once

#include "tendril/core/triangle_mesh.h"
#include "tendril/env/environment.h"
#include "tendril/lsystem/grammar.h"
#include "tendril/lsystem/lstring.h"
#include "tendril/plant/plant_model.h"
#include "tendril/plant/growth_flow.h"

#include <utility>
#include <vector>

namespace tendril::lsystem {

// Where the turtle starts: position, heading (H) and a hint for up (U, made perpendicular).
struct TurtleStart {
  Vec3 position = Vec3::Zero();
  Vec3 heading = Vec3::UnitY();
  Vec3 up = Vec3::UnitZ();
};

struct InterpretOptions {
  TurtleStart start;
  // Keys of interpretation rules' random numbers: the same step gives the same plant.
  uint64_t seed = 0;
  uint64_t plant = 0;
  uint32_t step = 0;       // the current derivation step (node ages count from module births)
  float stepTime = 1.0f;   // seconds of age per derivation step
  Limits limits;
  // Growth-Flow (seed 001): the wind the plant grew in, one unit of growth time per derivation
  // step, and its constants. A segment or leaf born in step b and drawn in step t has grown
  // through steps b+1 … t: its length, radius, leaf size and thickness carry those steps'
  // factors (eq. 7, 8, 16, 17), it is drawn turned toward the wind by eq. 9's α_t (Algorithm 1;
  // the turtle keeps its still-air heading for what follows), and a leaf that lived through a
  // wind above its strength is gone (Algorithm 2). Null: still air.
  const plant::GrowthFlowHistory* wind = nullptr;
  const plant::GrowthFlowSpecies* growthFlow = nullptr;
};

// The plant the string describes. Throws Error for run-time errors in interpretation rules and
// for turtle commands that cannot be drawn (zero headings, widths <= 0, unknown leaf shapes).
plant::PlantModel interpret(const Grammar& g, const LString& s, const InterpretOptions& options,
                            const double* globals);

// Writes the answers of every query module of `s` into its parameters. `env` may be null: an
// empty world (no surfaces, no lights, no strokes). Environment queries run in parallel.
void fillQueries(const Grammar& g, LString& s, const InterpretOptions& options, const double* globals,
                 const env::Environment* env);

// The polygons of a surface body (compile time): one mesh per colour index, in the turtle's
// start frame at scale 1.
std::vector<std::pair<int, TriangleMesh>> surfaceMeshes(const Grammar& g, const LString& body);

}  // namespace tendril::lsystem
