#include "tendril/wind/engine_wind.h"

#include "tendril/core/random.h"
#include "tendril/env/wind_field.h"
#include "tendril/wind/motion.h"

#include <Eigen/Dense>

namespace tendril::wind {

namespace {
constexpr uint64_t kPhasePurpose = purposeId("wind.engine-phase");
}  // namespace

std::vector<io::WindVertexNode> engineWindNodes(const plant::PlantModel& plant, const plant::GrowthFlowSpecies& species) {
  const size_t n = plant.nodeCount();
  std::vector<io::WindVertexNode> out(n);
  if (n == 0) return out;
  // WindMotion's torques in unit winds along x, y and z (its drag, its children's moments, its
  // supports), over its springs: column a of M_j is θ_j for the wind along axis a.
  WindMotion motion(plant, species);
  plant::PlantModel posed;
  std::vector<Eigen::Matrix3d> M(n, Eigen::Matrix3d::Zero());
  for (int a = 0; a < 3; ++a) {
    env::WindSettings ws;
    ws.velocity = Vec3::Unit(a);
    motion.step(0.0f, 0.0f, env::WindField(ws), posed);  // dt = 0: torques only, no sway
    for (size_t i = 0; i < n; ++i)
      M[i].col(a) = (motion.torque(i).cast<double>() / std::max(double(motion.stiffness(i)), 1e-12));
  }
  // Along the path from the root: L = Σ L_j (L_j the skew part of M_j: M_j ŵ ≈ L_j × ŵ) and
  // N = Σ L_j p_jᵀ, so that Σ_j (L_j · Â) p_j = Nᵀ Â. Parents come before their children.
  std::vector<Eigen::Vector3d> L(n);
  std::vector<Eigen::Matrix3d> N(n);
  std::vector<uint32_t> branch(n);  // the first node of the node's branch (its order starts there)
  uint16_t highest = 0;
  for (size_t i = 0; i < n; ++i) highest = std::max(highest, plant.order[i]);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Matrix3d& m = M[i];
    const Eigen::Vector3d own(0.5 * (m(2, 1) - m(1, 2)), 0.5 * (m(0, 2) - m(2, 0)), 0.5 * (m(1, 0) - m(0, 1)));
    const Eigen::Vector3d p = plant.position[i].cast<double>();
    const int32_t q = plant.parent[i];
    L[i] = own;
    N[i] = own * p.transpose();
    branch[i] = uint32_t(i);
    if (q >= 0) {
      L[i] += L[size_t(q)];
      N[i] += N[size_t(q)];
      if (plant.order[size_t(q)] == plant.order[i]) branch[i] = branch[size_t(q)];
    }
    io::WindVertexNode& r = out[i];
    const double length = L[i].norm();
    r.pivot = plant.position[i];
    if (length > 0.0) {
      const Eigen::Vector3d axis = L[i] / length;
      // Σ λ_j = L · Â = |L|.
      r.pivot = (N[i].transpose() * axis / length).cast<float>();
    }
    r.lever = L[i].cast<float>();
    r.level = highest > 0 ? float(plant.order[i]) / float(highest) : 0.0f;
    r.phase = float(mix64(uint64_t(branch[i]) ^ kPhasePurpose) >> 40) / float(uint64_t(1) << 24);
    // The natural period of eq. 1 (WindMotion keeps it within its limits).
    const double period = kTwoPi * std::sqrt(double(motion.inertia(i)) / std::max(double(motion.stiffness(i)), 1e-12));
    r.period = float(std::clamp((period - kEngineMinPeriod) / (kEngineMaxPeriod - kEngineMinPeriod), 0.0, 1.0));
  }
  return out;
}

io::WindTables engineWindTables(const std::vector<plant::PlantModel>& plants,
                                const std::vector<plant::GrowthFlowSpecies>& species) {
  io::WindTables out(plants.size());
  for (size_t i = 0; i < plants.size(); ++i)
    out[i] = engineWindNodes(plants[i], i < species.size() ? species[i] : plant::GrowthFlowSpecies{});
  return out;
}

}  // namespace tendril::wind
