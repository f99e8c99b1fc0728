#include "tendril/climb/species.h"

#include "tendril/climb/species_schema.h"

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


const schema::Schema<ClimbSpecies>& climbSpeciesSchema() {
  using S = ClimbSpecies;
  static const S d;  // the defaults are the struct's
  static const schema::Schema<S> schema{
      "climbing species",
      {
          schema::number<S>("segment_length", &S::segmentLength, d.segmentLength, 1e-4, 10.0, "m", "segment length",
                            "length of a shoot's first internode segment"),
          schema::number<S>("radius", &S::radius, d.radius, 1e-5, 1.0, "m", "radius", "radius of a shoot's first segment"),
          schema::number<S>("leaf_size", &S::leafSize, d.leafSize, 0.0, 5.0, "m", "leaf size",
                            "blade length of a shoot's first leaves"),
          schema::number<S>("min_length", &S::minLength, d.minLength, 0.0, 10.0, "m", "min length",
                            "a tip whose segments become shorter than this dies"),
          schema::number<S>("min_radius", &S::minRadius, d.minRadius, 1e-6, 1.0, "m", "min radius",
                            "radii never drop below this"),
          schema::vec3<S>("branch_falloff", &S::branchFalloff, d.branchFalloff, 0.05, 1.0, "", "branch falloff",
                          "a lateral shoot's start values (radius, length, leaf size) from its parent shoot's"),
          schema::boolean<S>("pipe_model", &S::pipeModel, d.pipeModel, "pipe model",
                             "thicken parents so that they carry their children"),
          schema::number<S>("adhesion_distance", &S::adhesionDistance, d.adhesionDistance, 0.0, 10.0, "m",
                            "adhesion distance", "a tip climbs when a surface is this close"),
          schema::number<S>("surface_offset", &S::surfaceOffset, d.surfaceOffset, 1e-4, 1.0, "m", "surface offset",
                            "segments keep at least this far from surfaces"),
          schema::number<S>("surface_hold", &S::surfaceHold, d.surfaceHold, 0.0, 1.0, "", "surface hold",
                            "probability that a tip about to leave every surface is bent back onto it"),
          schema::integer<S>("max_unsupported", &S::maxUnsupported, d.maxUnsupported, 0, 1000000, "max unsupported",
                             "a tip dies after this many segments in a row without support (0 = never)"),
          schema::number<S>("crowding_radius", &S::crowdingRadius, d.crowdingRadius, 0.0, 10.0, "m", "crowding radius",
                            "where segment ends are counted for crowding"),
          schema::integer<S>("crowding_limit", &S::crowdingLimit, d.crowdingLimit, 1, 100000, "crowding limit",
                             "segment ends within the crowding radius where tips die"),
          schema::integer<S>("max_segments", &S::maxSegments, d.maxSegments, 1, 50000000, "max segments",
                             "per plant; growth stops with a warning"),
      }};
  return schema;
}

const schema::Schema<ClimbSpecies>& climbTropismsSchema() {
  using S = ClimbSpecies;
  static const S d;
  static const schema::Schema<S> schema{
      "climbing species' tropisms",
      {
          schema::number<S>("gravity", &S::gravity, d.gravity, 0.0, 3.0, "", "gravity", "downward pull when not climbing"),
          schema::number<S>("light", &S::light, d.light, 0.0, 3.0, "", "light", "pull toward the lights where exposed"),
          schema::number<S>("light_ambient", &S::lightAmbient, d.lightAmbient, 0.0, 1.0, "", "light ambient",
                            "fraction of the light pull kept in shade"),
          schema::number<S>("random", &S::randomness, d.randomness, 0.0, 3.0, "", "random",
                            "a random direction per segment"),
          schema::number<S>("adhesion", &S::adhesion, d.adhesion, 0.0, 3.0, "", "adhesion",
                            "toward the nearest surface, when climbing"),
          schema::number<S>("up", &S::up, d.up, 0.0, 3.0, "", "up", "upward, when climbing"),
          schema::direction<S>("direction", &S::userDirection, d.userDirection, "direction",
                               "a user direction (pseudo-tropism)"),
          schema::number<S>("direction_strength", &S::userDirectionStrength, d.userDirectionStrength, 0.0, 3.0, "",
                            "direction strength", "weight of the user direction"),
          schema::number<S>("wind", &S::windStrength, d.windStrength, 0.0, 3.0, "", "wind",
                            "along the scene's wind, per m/s of wind"),
          schema::number<S>("attraction", &S::attraction, d.attraction, 0.0, 3.0, "", "attraction",
                            "toward painted attractor strokes"),
      }};
  return schema;
}

const schema::Schema<ClimbSpecies>& climbDecreaseSchema() {
  using S = ClimbSpecies;
  static const S d;
  static const schema::Schema<S> schema{
      "climbing species' decrease",
      {
          schema::number<S>("radius", &S::decreaseRadius, d.decreaseRadius, 0.5, 1.0, "", "radius",
                            "factor on the radius per decrease rule"),
          schema::number<S>("length", &S::decreaseLength, d.decreaseLength, 0.5, 1.0, "", "length",
                            "factor on the segment length per decrease rule"),
          schema::number<S>("leaf_size", &S::decreaseLeafSize, d.decreaseLeafSize, 0.5, 1.0, "", "leaf size",
                            "factor on the leaf size per decrease rule"),
      }};
  return schema;
}

void readClimbSpecies(JsonObject& o, ClimbSpecies& s, const std::string& baseDir) {
  s.name = o.string("name", s.name);
  s.description = o.string("description", s.description);
  o.markRead("model");  // the file's model tag, checked by the caller

  schema::readOver(o, climbSpeciesSchema(), s);
  if (auto d = o.optionalObject("decrease")) {
    schema::readOver(*d, climbDecreaseSchema(), s);
    d->finish();
  }
  if (auto t = o.optionalObject("tropisms")) {
    schema::readOver(*t, climbTropismsSchema(), s);
    s.userDirection = s.userDirection.normalized();  // as written there; used normalised
    t->finish();
  }
  // Angles convert in float here (as the presets always have); they are not in the
  // descriptions, whose angles convert in double.
  s.releaseAngle = o.angle("release_angle", degrees(s.releaseAngle), 0.0, 180.0);

  if (const Json* v = o.find("branch_angle")) {
    if (!v->is_array() || v->size() != 2 || !(*v)[0].is_number() || !(*v)[1].is_number())
      throw o.error("branch_angle", "expected [min, max] in degrees, got " + describeJson(*v));
    double lo = (*v)[0].get<double>(), hi = (*v)[1].get<double>();
    if (!(lo >= 0 && hi <= 90 && lo <= hi))
      throw o.error("branch_angle", "must satisfy 0 <= min <= max <= 90 (degrees)");
    s.branchAngleMin = radians(float(lo));
    s.branchAngleMax = radians(float(hi));
  }

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
}

}  // namespace tendril::climb
