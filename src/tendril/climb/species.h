// Species of the climbing-growth model (seed 003): shared, immutable settings; a plant's
// runtime state lives in ClimbPlant. Every field has a default (Japanese ivy, from seed 003's
// observations) and a documented range; docs/species.md describes each.
#pragma once

#include "tendril/core/math.h"
#include "tendril/plant/plant_model.h"
#include "tendril/plant/growth_flow.h"

#include <string>
#include <vector>

namespace tendril {
class JsonObject;
}

namespace tendril::climb {

// Seed 003, Table 1. Each rule runs every `every` segments of a tip with `probability`
// (Program 1). Collision avoidance, when listed, guards every segment before it is added.
enum class RuleKind { Tropism, Decrease, CollisionAvoidance, Die, PlaceLeaf, Branch };

struct Rule {
  RuleKind kind = RuleKind::Tropism;
  int every = 1;
  float probability = 1.0f;
};

const char* ruleName(RuleKind kind);

struct ClimbSpecies {
  std::string name = "japanese-ivy";
  std::string description;

  // Shoot start values and their per-segment decrease (seed 003 eq. 8).
  float segmentLength = 0.04f;  // m
  float radius = 0.006f;        // m
  float leafSize = 0.10f;       // blade length (m)
  float decreaseRadius = 0.97f;
  float decreaseLength = 0.97f;
  float decreaseLeafSize = 0.94f;
  float minLength = 0.004f;     // a tip whose segments get shorter dies (m)
  float minRadius = 0.0008f;    // radii never drop below (m)
  // A lateral shoot starts from its parent shoot's start values times these factors
  // (radius, length, leaf size): each shoot repeats eq. 8's decrease from its base.
  Vec3 branchFalloff = Vec3(0.8f, 0.95f, 0.95f);
  bool pipeModel = true;  // thicken parents to carry their children (seed 003 §6, pipe model)

  // Tropism strengths (seed 003 eq. 6–7): the tip turns toward the weighted sum.
  float gravity = 0.12f;         // downward, only when not climbing
  float light = 0.08f;           // toward the lights
  float lightAmbient = 0.3f;     // fraction of the light pull kept in full shade (sky light)
  float randomness = 0.16f;      // random direction per segment
  float adhesion = 0.35f;        // toward the nearest surface, only when climbing
  // Eq. 7's upward pseudo-tropism v_up, only when climbing: a tip near a support "ceases to be
  // affected by gravity and instead starts to grow upwards, clinging to the nearest object"
  // (seed 003 §3.6). The ivy's value makes it climb a wall in shade as well as in the sun and
  // still spread sideways (docs/species.md gives the figures).
  float up = 0.03f;
  Vec3 userDirection = Vec3::UnitY();
  float userDirectionStrength = 0.0f;  // pseudo-tropism toward a user direction
  float windStrength = 0.0f;           // pseudo-tropism along the wind (per m/s)
  float attraction = 0.5f;             // toward painted attractor strokes

  float adhesionDistance = 0.08f;  // the tip climbs when a surface is this close (m)
  // Surfaces whose normal lies within this angle of the growth direction do not hold the tip:
  // it is growing away from them (a seedling leaving the ground for a wall).
  float releaseAngle = radians(50.0f);
  float surfaceOffset = 0.012f;    // segments keep at least this far from surfaces (m)
  // Probability per segment that a climbing tip about to leave every surface within reach is
  // bent back onto its support (ivy's adhesive roots; what makes it wrap round edges). The
  // rest of the time the shoot breaks free into the air.
  float surfaceHold = 0.95f;
  // A tip dies after this many segments in a row without support (ivy cannot stand on its
  // own); 0 = never.
  int maxUnsupported = 6;

  // Branching (seed 003 §3.7): lateral shoots leave 35–40° from the growth direction.
  float branchAngleMin = radians(35.0f);
  float branchAngleMax = radians(40.0f);
  // Crowding: no branch, and the tip dies, where this many segments (of any plant) already
  // lie within crowdingRadius (in wind, times the shoot's eq. 8 length factor: see
  // ClimbSystem::growTip). 0 disables.
  float crowdingRadius = 0.06f;  // m
  int crowdingLimit = 8;

  // Leaves (seed 003 §3.8, §3.10): two blades per leaf node, lying parallel to the support.
  std::vector<plant::LeafShape> leafShapes = {
      {"builtin:ivy-0", 1.0f, Vec3::Ones()}, {"builtin:ivy-1", 1.0f, Vec3::Ones()}, {"builtin:ivy-2", 1.0f, Vec3::Ones()}};
  float leafSpread = radians(55.0f);  // angle of each blade from the growth direction
  float leafJitter = radians(12.0f);  // random extra rotation of each blade
  float leafPetiole = 0.01f;          // petiole length in the surface plane (m)
  float leafLift = 0.004f;            // blade height above the stem surface (m)
  float leafThickness = 0.0004f;      // m

  plant::BarkMaterial bark;

  std::vector<Rule> rules = {
      {RuleKind::Tropism, 1, 1.0f},   {RuleKind::CollisionAvoidance, 1, 1.0f},
      {RuleKind::Decrease, 1, 1.0f},  {RuleKind::PlaceLeaf, 2, 1.0f},
      {RuleKind::Branch, 3, 0.6f},    {RuleKind::Die, 10, 0.02f},
  };

  int maxSegments = 500000;  // per plant; growth stops (with a warning) when reached

  // How growth answers the wind (seed 001, Growth-Flow): per segment the tip's length, radius,
  // leaf size and leaf thickness take eq. 7/8/16/17's factors, the tip turns downwind by eq. 9,
  // and no leaf is placed where the wind would tear it off. See docs/wind.md.
  plant::GrowthFlowSpecies growthFlow;
};

// Reads the species fields present in `o` over `s` (absent fields keep their value), so a
// preset can be refined by overrides. Strict: unknown keys, wrong types and out-of-range
// values throw Error naming the file and JSON pointer. `baseDir` resolves texture paths.
void readClimbSpecies(JsonObject& o, ClimbSpecies& s, const std::string& baseDir);

}  // namespace tendril::climb
