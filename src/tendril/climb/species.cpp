#include "tendril/climb/species.h"

#include "tendril/core/json_reader.h"
#include "tendril/plant/species_materials.h"

#include <nlohmann/json.hpp>


namespace tendril::climb {

const char* ruleName(RuleKind kind) {
  switch (kind) {
    case RuleKind::Tropism: return "tropism";
    case RuleKind::Decrease: return "decrease";
    case RuleKind::CollisionAvoidance: return "collision_avoidance";
    case RuleKind::Die: return "die";
    case RuleKind::PlaceLeaf: return "place_leaf";
    case RuleKind::Branch: return "branch";
  }
  return "?";
}


void readClimbSpecies(JsonObject& o, ClimbSpecies& s, const std::string& baseDir) {
  s.name = o.string("name", s.name);
  s.description = o.string("description", s.description);
  o.markRead("model");  // the file's model tag, checked by the caller

  s.segmentLength = o.numberf("segment_length", s.segmentLength, 1e-4, 10.0);
  s.radius = o.numberf("radius", s.radius, 1e-5, 1.0);
  s.leafSize = o.numberf("leaf_size", s.leafSize, 0.0, 5.0);
  if (auto d = o.optionalObject("decrease")) {
    s.decreaseRadius = d->numberf("radius", s.decreaseRadius, 0.5, 1.0);
    s.decreaseLength = d->numberf("length", s.decreaseLength, 0.5, 1.0);
    s.decreaseLeafSize = d->numberf("leaf_size", s.decreaseLeafSize, 0.5, 1.0);
    d->finish();
  }
  s.minLength = o.numberf("min_length", s.minLength, 0.0, 10.0);
  s.minRadius = o.numberf("min_radius", s.minRadius, 1e-6, 1.0);
  s.branchFalloff = o.vec3("branch_falloff", s.branchFalloff, 0.05, 1.0);
  s.pipeModel = o.boolean("pipe_model", s.pipeModel);

  if (auto t = o.optionalObject("tropisms")) {
    s.gravity = t->numberf("gravity", s.gravity, 0.0, 3.0);
    s.light = t->numberf("light", s.light, 0.0, 3.0);
    s.lightAmbient = t->numberf("light_ambient", s.lightAmbient, 0.0, 1.0);
    s.randomness = t->numberf("random", s.randomness, 0.0, 3.0);
    s.adhesion = t->numberf("adhesion", s.adhesion, 0.0, 3.0);
    s.userDirection = t->direction("direction", s.userDirection);
    s.userDirectionStrength = t->numberf("direction_strength", s.userDirectionStrength, 0.0, 3.0);
    s.windStrength = t->numberf("wind", s.windStrength, 0.0, 3.0);
    s.attraction = t->numberf("attraction", s.attraction, 0.0, 3.0);
    t->finish();
  }
  s.adhesionDistance = o.numberf("adhesion_distance", s.adhesionDistance, 0.0, 10.0);
  s.releaseAngle = o.angle("release_angle", degrees(s.releaseAngle), 0.0, 180.0);
  s.surfaceOffset = o.numberf("surface_offset", s.surfaceOffset, 1e-4, 1.0);
  s.surfaceHold = o.numberf("surface_hold", s.surfaceHold, 0.0, 1.0);
  s.maxUnsupported = int(o.integer("max_unsupported", s.maxUnsupported, 0, 1000000));

  if (const Json* v = o.find("branch_angle")) {
    if (!v->is_array() || v->size() != 2 || !(*v)[0].is_number() || !(*v)[1].is_number())
      throw o.error("branch_angle", "expected [min, max] in degrees, got " + describeJson(*v));
    double lo = (*v)[0].get<double>(), hi = (*v)[1].get<double>();
    if (!(lo >= 0 && hi <= 90 && lo <= hi))
      throw o.error("branch_angle", "must satisfy 0 <= min <= max <= 90 (degrees)");
    s.branchAngleMin = radians(float(lo));
    s.branchAngleMax = radians(float(hi));
  }
  s.crowdingRadius = o.numberf("crowding_radius", s.crowdingRadius, 0.0, 10.0);
  s.crowdingLimit = int(o.integer("crowding_limit", s.crowdingLimit, 1, 100000));

  if (auto l = o.optionalObject("leaf")) {
    plant::readLeafShapes(*l, s.leafShapes, baseDir);
    s.leafSpread = l->angle("spread", degrees(s.leafSpread), 0.0, 90.0);
    s.leafJitter = l->angle("jitter", degrees(s.leafJitter), 0.0, 45.0);
    s.leafPetiole = l->numberf("petiole", s.leafPetiole, 0.0, 1.0);
    s.leafLift = l->numberf("lift", s.leafLift, 0.0, 1.0);
    s.leafThickness = l->numberf("thickness", s.leafThickness, 0.0, 0.1);
    l->finish();
  }
  if (auto b = o.optionalObject("bark")) plant::readBark(*b, s.bark, baseDir);
  if (auto g = o.optionalObject("growth_flow")) plant::readGrowthFlow(*g, s.growthFlow);

  if (const Json* rules = o.find("rules")) {
    if (!rules->is_array()) throw o.error("rules", "expected an array of rules, got " + describeJson(*rules));
    std::vector<JsonObject> items = o.objectArray("rules");
    s.rules.clear();
    for (JsonObject& r : items) {
      std::string kind = r.choice("rule", "", {"tropism", "decrease", "collision_avoidance", "die", "place_leaf", "branch"});
      if (!r.has("rule")) throw r.error("rule", "is required");
      Rule rule;
      for (RuleKind k : {RuleKind::Tropism, RuleKind::Decrease, RuleKind::CollisionAvoidance, RuleKind::Die,
                         RuleKind::PlaceLeaf, RuleKind::Branch})
        if (kind == ruleName(k)) rule.kind = k;
      rule.every = int(r.integer("every", 1, 1, 100000));
      rule.probability = r.numberf("probability", 1.0f, 0.0, 1.0);
      if (rule.kind == RuleKind::CollisionAvoidance && (rule.every != 1 || rule.probability != 1.0f))
        throw r.error("collision avoidance guards every segment: it takes every = 1 and probability = 1 "
                      "(leave the rule out to let the plant grow through obstacles)");
      r.finish();
      s.rules.push_back(rule);
    }
  }
  s.maxSegments = int(o.integer("max_segments", s.maxSegments, 1, 50000000));
}

}  // namespace tendril::climb
