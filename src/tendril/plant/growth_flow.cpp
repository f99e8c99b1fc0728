#include "tendril/plant/growth_flow.h"

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"

#include <algorithm>
#include <cmath>

namespace tendril::plant {

void readGrowthFlow(JsonObject& o, GrowthFlowSpecies& s) {
  s.windMin = o.numberf("wind_min", s.windMin, 0.0, 100.0);
  s.windMax = o.numberf("wind_max", s.windMax, 0.0, 200.0);
  if (s.windMax <= s.windMin) throw o.error("wind_max", "must be greater than wind_min");
  s.radiusRate = o.numberf("radius_rate", s.radiusRate, 0.0, 1.0);
  s.radiusSensitivity = o.numberf("radius_sensitivity", s.radiusSensitivity, 0.0, 1.0);
  s.lengthSensitivity = o.numberf("length_sensitivity", s.lengthSensitivity, 0.0, 1.0);
  s.maxLength = o.numberf("max_length", s.maxLength, 0.0, 100.0);
  s.angle0 = o.angle("angle0", degrees(s.angle0), 0.0, 90.0);
  s.angleConversion = o.numberf("angle_conversion", s.angleConversion, 0.0, 1.0);
  s.angleSensitivity = o.numberf("angle_sensitivity", s.angleSensitivity, 0.0, 1.0);
  s.leafThicknessRate = o.numberf("leaf_thickness_rate", s.leafThicknessRate, 0.0, 1.0);
  s.leafThicknessSensitivity = o.numberf("leaf_thickness_sensitivity", s.leafThicknessSensitivity, 0.0, 1.0);
  s.leafRadiusSensitivity = o.numberf("leaf_radius_sensitivity", s.leafRadiusSensitivity, 0.0, 1.0);
  s.petioleStrength = o.numberf("petiole_strength", s.petioleStrength, 0.0, 1e3);
  s.bladeStrength = o.numberf("blade_strength", s.bladeStrength, 0.0, 1e3);
  s.strengthToWind = o.numberf("strength_to_wind", s.strengthToWind, 0.0, 1e3);
  s.petioleBendRate = o.angle("petiole_bend_rate", degrees(s.petioleBendRate), 0.0, 360.0);
  s.bladeBendRate = o.angle("blade_bend_rate", degrees(s.bladeBendRate), 0.0, 360.0);
  s.twistRate = o.angle("twist_rate", degrees(s.twistRate), 0.0, 360.0);
  s.vibrateRate = o.angle("vibrate_rate", degrees(s.vibrateRate), 0.0, 360.0);
  s.petioleBendLimit = o.angle("petiole_bend_limit", degrees(s.petioleBendLimit), 0.0, 90.0);
  s.bladeBendLimit = o.angle("blade_bend_limit", degrees(s.bladeBendLimit), 0.0, 90.0);
  s.twistLimit = o.angle("twist_limit", degrees(s.twistLimit), 0.0, 90.0);
  s.vibrateLimit = o.angle("vibrate_limit", degrees(s.vibrateLimit), 0.0, 90.0);
  s.youngModulus = o.numberf("young_modulus", s.youngModulus, 1e5, 1e12);
  s.woodDensity = o.numberf("wood_density", s.woodDensity, 10.0, 5000.0);
  s.dragCoefficient = o.numberf("drag_coefficient", s.dragCoefficient, 0.0, 10.0);
  s.leafMass = o.numberf("leaf_mass", s.leafMass, 0.0, 10.0);
  s.swayDamping = o.numberf("sway_damping", s.swayDamping, 0.01, 0.95);
  s.maxSwayAngle = o.angle("max_sway_angle", degrees(s.maxSwayAngle), 0.0, 90.0);
  s.growthUnits = uint32_t(o.integer("growth_units", s.growthUnits, 1, 100000));
  o.finish();
}

float windGrowthFactor(float w, float wMin, float wMax) {
  // eq. 6
  return std::min(1.0f, std::max(0.0f, (w - wMin) / (wMax - wMin)));
}

static double f(double w, const GrowthFlowSpecies& s) {
  return std::min(1.0, std::max(0.0, (w - s.windMin) / (double(s.windMax) - s.windMin)));
}

double radiusAt(double r0, double t, double w, const GrowthFlowSpecies& s) {
  double dr = 1.0 + s.radiusSensitivity * f(w, s);  // eq. 7
  return r0 * std::pow(1.0 + s.radiusRate * dr, t);
}

double lengthAt(double l0, double t, double w, double gl, const GrowthFlowSpecies& s) {
  double dl = 1.0 - s.lengthSensitivity * f(w, s);  // eq. 8
  double l = l0 * std::pow(gl * dl, t);
  return s.maxLength > 0.0f ? std::min(l, double(s.maxLength)) : l;  // Algorithm 1: l_t ≤ l_max
}

double angleAt(double t, double w, const GrowthFlowSpecies& s) {
  double da = double(s.angleConversion) * s.angleSensitivity * f(w, s);  // eq. 9
  return s.angle0 * std::pow(1.0 + da, t);
}

double leafThicknessAt(double h0, double t, double w, const GrowthFlowSpecies& s) {
  double dh = 1.0 + s.leafThicknessSensitivity * f(w, s);  // eq. 16 (reconstructed, see header)
  return h0 * std::pow(1.0 + s.leafThicknessRate * dh, t);
}

double leafRadiusAt(double d0, double t, double w, double gd, const GrowthFlowSpecies& s) {
  double dd = 1.0 - s.leafRadiusSensitivity * f(w, s);  // eq. 17 (reconstructed, see header)
  return d0 * std::pow(gd * dd, t);
}

GrowthFlowStep growthStep(float w, const GrowthFlowSpecies& s) {
  GrowthFlowStep g;
  g.f = windGrowthFactor(w, s.windMin, s.windMax);
  if (!g.active()) return g;  // exactly the still-air growth
  g.radius = (1.0f + s.radiusRate * (1.0f + s.radiusSensitivity * g.f)) / (1.0f + s.radiusRate);
  g.length = 1.0f - s.lengthSensitivity * g.f;
  g.leafThickness =
      (1.0f + s.leafThicknessRate * (1.0f + s.leafThicknessSensitivity * g.f)) / (1.0f + s.leafThicknessRate);
  g.leafRadius = 1.0f - s.leafRadiusSensitivity * g.f;
  g.angleGrowth = s.angleConversion * s.angleSensitivity * g.f;
  return g;
}

float nextGrowthAngle(float angle, const GrowthFlowStep& step) {
  if (!step.active()) return angle;
  return std::min(angle * (1.0f + step.angleGrowth), kPi);  // eq. 9, α_t = α_{t−1} (1 + Δα)
}

Vec3 windGrowthDirection(const Vec3& direction, const Vec3& wind, float angle) {
  float speed = wind.norm();
  if (speed <= 0.0f || angle <= 0.0f) return direction;
  Vec3 w = wind / speed;
  Vec3 u = direction.cross(w);  // Algorithm 1: u = b × w
  float s = u.norm();
  if (s < 1e-6f) return direction;  // already along (or against) the wind
  float toWind = std::atan2(s, direction.dot(w));
  return (Eigen::AngleAxisf(std::min(angle, toWind), u / s) * direction).normalized();
}

void GrowthFlowHistory::record(const Vec3& wind, const GrowthFlowSpecies& s) {
  const float speed = wind.norm();
  const GrowthFlowStep g = growthStep(speed, s);
  Sums next = sums_.back();
  if (g.active()) {
    next.radius += std::log(double(g.radius));
    next.length += std::log(double(g.length));
    next.leafThickness += std::log(double(g.leafThickness));
    next.leafRadius += std::log(double(g.leafRadius));
    next.angle += std::log1p(double(g.angleGrowth));
  }
  sums_.push_back(next);
  active_.push_back(active_.back() + (g.active() ? 1u : 0u));
  torn_.push_back(torn_.back() + (g.active() && leafDetaches(speed, s) ? 1u : 0u));
  winds_.push_back(wind);
}

GrowthFlowHistory::Factors GrowthFlowHistory::organ(uint32_t birth, uint32_t now, const GrowthFlowSpecies& s) const {
  Factors f;
  now = std::min(now, units());
  const uint32_t end = std::min(birth > 0 ? birth - 1 : 0u, now);  // its last unit of growth
  const uint32_t start = end - std::min(end, s.growthUnits);        // units start+1 … end
  f.torn = torn_[now] > torn_[start];
  f.active = active_[end] > active_[start];
  if (!f.active) return f;  // exactly the still-air organ
  const Sums& a = sums_[start];
  const Sums& b = sums_[end];
  f.radius = float(std::exp(b.radius - a.radius));
  f.length = float(std::exp(b.length - a.length));
  f.leafThickness = float(std::exp(b.leafThickness - a.leafThickness));
  f.leafRadius = float(std::exp(b.leafRadius - a.leafRadius));
  // eq. 9 from α_0 over the windy units: α_t = α_0 Π (1 + Δα), at most π.
  f.angle = float(std::min(double(kPi), double(s.angle0) * std::exp(b.angle - a.angle)));
  f.wind = winds_[end];
  return f;
}

void GrowthFlowHistory::restore(std::vector<Sums> sums, std::vector<uint32_t> active, std::vector<uint32_t> torn,
                                std::vector<Vec3> winds) {
  if (sums.empty() || sums.size() != active.size() || sums.size() != torn.size() || sums.size() != winds.size())
    throw Error("", "", "inconsistent Growth-Flow history");
  sums_ = std::move(sums);
  active_ = std::move(active);
  torn_ = std::move(torn);
  winds_ = std::move(winds);
}

}  // namespace tendril::plant
