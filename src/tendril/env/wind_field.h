// The wind w(x, t) every growth and motion model samples (DESIGN.md: the Environment answers
// "wind velocity at (x, t)").
//
// Three modes:
//  * constant — the prevailing velocity everywhere, plus the emitters' jets;
//  * gusty    — the prevailing wind modulated by smooth value noise: gust fronts travel with the
//               wind (the noise is a function of t − (x·ŵ)/|w| and of the position across the
//               wind), the speed varies by ±gustStrength and the direction wanders by ±gustTurn
//               about +Y; plus the emitters' jets;
//  * sph      — the velocity of simulated air (seed 000 §5.3) from an AirFlow the owner of the
//               simulation installs (wind/sph.h); where there is no air it falls back to the
//               constant mode.
// An emitter (seed 000 §5.3: position, direction, speed, rate, area) blows a round jet of the
// given radius that widens by `spread` and slows as its area grows (momentum flux conserved)
// until `reach`; its rate is the number of air particles per second it spawns in sph mode.
//
// The noise is counter-based (keyed by the wind's seed), so w(x, t) is a pure function: the
// same scene gives the same wind on any thread.
#pragma once

#include "tendril/core/math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace tendril::env {

struct WindEmitter {
  Vec3 position = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();  // unit
  float speed = 5.0f;              // m/s at the nozzle
  float radius = 0.5f;             // m (the paper's area is π radius²)
  float reach = 10.0f;             // m along the direction
  float spread = radians(8.0f);    // half-angle the jet widens by
  float rate = 0.0f;               // air particles per second in sph mode (0 = from speed and area)
};

enum class WindMode { Constant, Gusty, Sph };

struct WindSettings {
  WindMode mode = WindMode::Constant;
  Vec3 velocity = Vec3::Zero();  // prevailing wind (m/s)
  float gustStrength = 0.4f;     // gusty: speed varies by ± this fraction of the prevailing speed
  float gustPeriod = 3.0f;       // s between independent gusts
  float gustScale = 6.0f;        // m across the wind between independent gusts
  float gustTurn = radians(12.0f);  // direction wander about +Y
  uint64_t seed = 0;
  std::vector<WindEmitter> emitters;

  bool calm() const;  // no wind anywhere, ever
};

// Simulated air the sph mode samples.
class AirFlow {
 public:
  virtual ~AirFlow() = default;
  // Air velocity at p; `covered` false where no air particle is near.
  virtual Vec3 velocityAt(const Vec3& p, bool* covered) const = 0;
};

class WindField {
 public:
  WindField() = default;
  explicit WindField(WindSettings settings) : settings_(std::move(settings)) { prepare(); }

  const WindSettings& settings() const { return settings_; }
  void setSettings(WindSettings settings) {
    settings_ = std::move(settings);
    prepare();
  }
  // The simulated air for sph mode (not owned; null = none).
  void setAirFlow(const AirFlow* air) { air_ = air; }

  Vec3 sample(const Vec3& p, float t) const;
  // The prevailing wind modulated by gusts, without the emitters' jets.
  Vec3 ambient(const Vec3& p, float t) const;
  // One emitter's jet at p.
  static Vec3 jet(const WindEmitter& e, const Vec3& p);
  // Smooth value noise in [−1, 1] over the plane (continuous, C2), keyed by seed.
  static float noise(float u, float v, uint64_t seed);
  // The noise's interpolation weight, 6x⁵ − 15x⁴ + 10x³ (zero first and second derivatives at
  // 0 and 1).
  static float quintic(float x) { return x * x * x * (x * (x * 6.0f - 15.0f) + 10.0f); }

 private:
  friend class GustSampler;
  void prepare();  // the frame below, from settings_
  // The gusty wind from its two noise values: the prevailing wind scaled by 1 + gustStrength ·
  // gust and turned by gustTurn · turn about +Y.
  Vec3 gustWind(float gust, float turn) const {
    // dir turned by θ about +Y: (x cos θ + z sin θ, y, z cos θ − x sin θ); θ is at most
    // gustTurn, mostly a few degrees (sinCos's short series).
    float c, sn;
    sinCos(settings_.gustTurn * turn, &sn, &c);
    const Vec3& dir = dir_;
    const Vec3 turned(dir.x() * c + dir.z() * sn, dir.y(), dir.z() * c - dir.x() * sn);
    return speed_ * std::max(0.0f, 1.0f + settings_.gustStrength * gust) * turned;
  }

  WindSettings settings_;
  const AirFlow* air_ = nullptr;
  // The prevailing wind's speed, direction and the horizontal direction across it (gusty).
  float speed_ = 0.0f;
  Vec3 dir_ = Vec3::UnitX(), across_ = Vec3::UnitX();
  bool acrossIsX_ = true;  // a vertical wind: its "across" position is x
};

// The gusty wind (WindField::ambient) at the same points frame after frame, bit for bit as
// ambient(p, t) gives it, for models that sample every node of a plant each frame
// (Growth-Flow motion). What depends on a point alone — its time of flight from the plane
// through the origin, its place across the wind and the noise's weights across — is computed
// when the points or the wind's gust settings change; each frame, the noise's lattice values
// the points span (gusts are seconds and metres across, so a plant spans a handful) are hashed
// once into a table. A span too large for the table falls back to ambient() per point.
class GustSampler {
 public:
  void prepare(const WindField& field, const Vec3* points, size_t count);
  // prepare() was called for `count` points and a field whose ambient wind is this one's.
  bool preparedFor(const WindField& field, size_t count) const;
  // Builds the lattice table for time t; then ambient(k) is field.ambient(points[k], t).
  void beginFrame(float t);
  // This frame reads the table (false: per point, or no gusts).
  bool tabled() const { return tabled_; }
  Vec3 ambient(size_t k) const {
    if (!tabled_) return field_.ambient(position_[k], t_);
    const float tau = (t_ - flight_[k]) / field_.settings_.gustPeriod;
    const float gust = tableNoise(table_[0], tau, row_[0][k], b_[0][k]);
    const float turn = tableNoise(table_[1], tau + 101.3f, row_[1][k], b_[1][k]);
    return field_.gustWind(gust, turn);
  }
  // ambient(k + l) for l = 0…3 as x[l], y[l], z[l] (the same bits; four lanes at once).
  void ambient4(size_t k, float* x, float* y, float* z) const;

 private:
  struct Table {
    int64_t firstColumn = 0;  // lattice index along time of the first column
    int32_t firstRow = 0, rows = 0;  // lattice rows across [firstRow, firstRow + rows)
    std::vector<float> values;       // column-major: (column c, row r) at c · rows + r
  };
  // WindField::noise(u, v) for v's row and weight kept per point.
  static float tableNoise(const Table& T, float u, int32_t row, float b) {
    const float fu = std::floor(u);
    const float a = WindField::quintic(u - fu);
    const float* L = T.values.data() + (int64_t(fu) - T.firstColumn) * T.rows + row;
    const float x0 = L[0] + a * (L[T.rows] - L[0]);
    const float x1 = L[1] + a * (L[T.rows + 1] - L[1]);
    return x0 + b * (x1 - x0);
  }

  WindField field_;  // a copy of the settings (and frame) the points were prepared for
  // Per point: its position, p · ŵ / |w| (s), and per noise its lattice row across the wind
  // (floor of the across coordinate, less the table's first row) and quintic weight across.
  std::vector<Vec3> position_;
  std::vector<float> flight_;
  std::vector<int32_t> row_[2];
  std::vector<float> b_[2];
  float flightMin_ = 0.0f, flightMax_ = 0.0f;
  Table table_[2];  // the gust noise and the turn noise
  bool tableable_ = false, tabled_ = false;
  float t_ = 0.0f;
};

}  // namespace tendril::env
