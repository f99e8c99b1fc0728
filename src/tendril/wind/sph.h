// Air as SPH particles, coupled both ways with plants (seed 000 §5.3).
//
// Weakly compressible SPH after Müller, Charypar & Gross 2003 ("Particle-based fluid
// simulation for interactive applications", MCG03): density by the poly6 kernel, pressure
// p = c²(ρ − ρ0) with the spiky kernel's gradient, viscosity with the viscosity kernel's
// Laplacian (seed 000 eq. 11–12). Or (SphSolver::PositionBased) the pressure as the
// multiplier of the density constraint ρ = ρ0, solved by position projections (Macklin &
// Müller 2013, "Position Based Fluids"), in a third of the substeps. Plants' bodies — the
// grown branch particles of a ParticleWorld, or any system's through models::AirCoupling —
// take part through an anisotropic kernel W(G(x − x_j)) whose tensor G comes from the body's
// ellipsoid (eq. 13, after Owen et al. 1997): they add to the air's density and push it by
// pressure like boundary particles, and they drag the air with a stem's cross-flow drag; the
// equal and opposite force becomes the body's external acceleration (a_e in eq. 1).
// Obstacles come from the Environment's signed distances; each face of the domain box is
// either closed (a wall) or open (particles leaving through it are removed).
//
// Determinism: every sum is gathered per particle in grid order, with no atomics; particles
// are spawned and removed sequentially. Results are bit-identical for any thread count.
// Units: metres, seconds, kilograms; see docs/sph.md for the equations and defaults.
#pragma once

#include "tendril/core/archive.h"
#include "tendril/core/math.h"
#include "tendril/env/wind_field.h"
#include "tendril/models/capabilities.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace tendril::env {
class Environment;
}

namespace tendril::wind {

// How the air's pressure is found.
enum class SphSolver {
  // MCG03's equation of state, p = c²(ρ − ρ0) + p_b, and explicit pressure forces: substeps
  // at the acoustic CFL, Δt ≤ cfl·h/(c + v_max) (8–9 per 25 ms frame in a 2–4 m/s wind).
  WeaklyCompressible,
  // Position-based fluids (Macklin & Müller 2013): the pressure as the multiplier of the
  // density constraint ρ/ρ0 = 1, solved by `iterations` Jacobi position projections per
  // substep; substeps at the flow's CFL, Δt ≤ cfl·h/v_max (2–3 per frame). Viscosity, plants
  // and walls as in the weakly compressible solver. See docs/sph.md, "Position-based solver".
  PositionBased,
};

// The kernel through which a plant's body meets the air (docs/sph.md, "Coupling with the plants").
enum class SphKernel {
  // Seed 000 eq. 13: W(G(x − x_j)), G mapping the body's own ellipsoid grown by h along every
  // axis onto the unit ball (support semi-axes a + h along the body, b + h across it).
  Anisotropic,
  // An ablation for comparing with eq. 13: the support a sphere of radius ∛(a b²) + h — the
  // body taken as a ball of its own volume, as isotropic solid particles are in a unified
  // solver (Macklin et al. 2014). Only the kernel changes; the drag stays a stem's cross-flow
  // drag. A long particle then meets the air only around its centre.
  Isotropic,
};

enum class SphBoundary {
  Outflow,  // particles leaving the domain box are removed
  Closed,   // the domain box's faces are walls
};

struct SphSettings {
  float restDensity = 1.25f;      // ρ0 (kg/m³), air near 10 °C at sea level
  float spacing = 0.05f;          // rest distance s between particles (m); a particle holds ρ0·s³
  float supportFactor = 2.0f;     // kernel support h = supportFactor · s (1.5–4)
  float soundSpeed = 10.0f;       // c (m/s): the equation of state p = c² (ρ − ρ0) + p_b, clamped at 0
  float backgroundPressure = 0.05f;  // p_b / (c²ρ0), closed domains only: air down to this deficit still pulls
  float viscosity = 0.02f;        // μ (Pa·s), artificial (air's own is 1.8e-5; see docs/sph.md)
  float dragCoefficient = 1.2f;   // C_d of a branch particle in cross-flow (a cylinder)
  SphKernel kernel = SphKernel::Anisotropic;  // plant bodies' kernel: eq. 13's, or isotropic (an ablation)
  float dt = 0.025f;              // frame step (s); use the plant world's step
  float cfl = 0.4f;               // substeps keep Δt ≤ cfl · h / (c + v_max) (PositionBased: cfl · h / v_max)
  int maxSubsteps = 64;           // per frame; more would be needed → the frame is clamped, warned once
  SphSolver solver = SphSolver::WeaklyCompressible;
  int iterations = 3;             // PositionBased: projections of the density constraint per substep (1–50)
  Vec3 domainMin = Vec3(-1, 0, -1);  // the simulated box (m)
  Vec3 domainMax = Vec3(1, 2, 1);
  // The domain box's faces: faces[2k] lies at domainMin[k], faces[2k + 1] at domainMax[k]
  // (k = 0, 1, 2 for x, y, z). All Outflow (the default): air that leaves is gone. All Closed:
  // a sealed box, with the background pressure. Mixed: a wind tunnel, say, closed but for its
  // outlet (no background pressure: an open face has no air outside to balance it).
  std::array<SphBoundary, 6> faces = {SphBoundary::Outflow, SphBoundary::Outflow, SphBoundary::Outflow,
                                      SphBoundary::Outflow, SphBoundary::Outflow, SphBoundary::Outflow};
  void setBoundary(SphBoundary b) { faces.fill(b); }
  bool closed(int face) const { return faces[size_t(face)] == SphBoundary::Closed; }
  bool allClosed() const {
    for (int f = 0; f < 6; ++f)
      if (!closed(f)) return false;
    return true;
  }
  size_t maxParticles = 1'000'000;  // emitters stop (warned once) at this many air particles
};

// A disc of the given radius, facing `direction`, spawning layers of particles at `speed`.
struct SphEmitter {
  Vec3 position = Vec3::Zero();        // disc centre (m), inside the domain
  Vec3 direction = Vec3(1, 0, 0);      // flow direction (normalised on add)
  float speed = 2.0f;                  // m/s, > 0
  float rate = 0.0f;                   // particles/s; 0 = the rest density's flow, ρ0·speed·area/m
  float radius = 0.25f;                // m
};

// Wall-clock seconds of the last step, per phase, and how many pairs its substeps met (for
// benchmarks, never for behaviour).
struct SphTimings {
  double neighbours = 0, density = 0, forces = 0, coupling = 0, obstacles = 0, total = 0;
  // The part of `coupling` spent once per frame: binning the plants and their gather of the air.
  double plantFrame = 0;
  int substeps = 0;
  // Summed over the substeps: air particles, their air neighbours (0 < r < h) and the plant
  // particles whose support holds them.
  uint64_t particles = 0, airPairs = 0, plantPairs = 0;
};

// An env::AirFlow: install it with Environment::setAirFlow for the wind field's sph mode.
class SphAir final : public env::AirFlow {
 public:
  // Throws Error naming the bad setting.
  explicit SphAir(const SphSettings& settings = {});
  ~SphAir() override;
  SphAir(SphAir&&) noexcept;
  SphAir& operator=(SphAir&&) noexcept;

  const SphSettings& settings() const { return settings_; }

  // Throws Error when the emitter is not finite, its speed, rate or radius is out of range
  // (a layer, the lattice in the disc's bounding square, may span at most four times
  // maxParticles sites), or its centre lies outside the domain.
  uint32_t addEmitter(const SphEmitter& emitter);
  // Throws the Error addEmitter would for the emitter (its location names the member),
  // changing nothing.
  void checkEmitter(const SphEmitter& emitter) const;
  const std::vector<SphEmitter>& emitters() const { return emitters_; }
  void clearEmitters();

  // Fills the box (clipped to the domain) with particles on a cubic lattice of the rest
  // spacing, moving at `velocity`; with an environment, sites closer than 0.45 s to an obstacle
  // are left out. Returns the number added. Throws Error when the box is empty or the
  // particles would exceed maxParticles.
  size_t fillBox(const Vec3& min, const Vec3& max, const Vec3& velocity = Vec3::Zero());
  size_t fillBox(const Vec3& min, const Vec3& max, const env::Environment& env,
                 const Vec3& velocity = Vec3::Zero());

  // One frame of settings().dt in as many substeps as stability needs. With `plants` (the
  // systems that take part, models::AirCoupling), their bodies (e.g. the grown branch particles
  // of a particle world) and the air act on each other: this overwrites each system's
  // airAcceleration() (every slot; zero for bodies outside the air) with the air's drag and
  // pressure on each body. Call it before the plants step, at their airTimeStep().
  void step(const env::Environment& env, std::span<models::AirCoupling* const> plants);
  // The same for one system, or none (null).
  void step(const env::Environment& env, models::AirCoupling* plants);

  // The air velocity w(x) (m/s) at p by SPH interpolation (eq. 12), Shepard-normalised where
  // the air is complete: Σ V_j v_j W / max(Σ V_j W, ½). It fades to zero at the edge of the
  // air and is zero where no air particle lies within h, and outside the domain.
  // Thread-safe between steps.
  Vec3 velocityAt(const Vec3& p) const;
  // The same; `covered` says whether any air particle lies within h of p.
  Vec3 velocityAt(const Vec3& p, bool* covered) const override;

  // --- state (dense: indices [0, count()); removing particles keeps the others' order and
  // new particles reuse the freed slots at the end) ---
  size_t count() const { return x_.size(); }
  const std::vector<Vec3>& positions() const { return x_; }
  const std::vector<Vec3>& velocities() const { return v_; }
  const std::vector<float>& densities() const { return rho_; }  // kg/m³, from the last substep
  float particleMass() const { return mass_; }   // kg
  float supportRadius() const { return h_; }     // h (m)
  float time() const { return time_; }
  uint64_t stepCount() const { return steps_; }
  const SphTimings& timings() const { return timings_; }
  // Grown branch particles of the plants that interacted with the air in the last step.
  size_t coupledPlantParticles() const;

  // The air's state: emitters, particles and the per-particle obstacle distances (sessions,
  // undo; sph_state.cpp). The settings are not written: loadState expects an SphAir made with
  // the same settings. Damaged input throws Error (from the reader).
  void saveState(ArchiveWriter& out) const;
  void loadState(ArchiveReader& in);

 private:
  struct Grid;
  struct Plants;
  struct Walls;

  void validate() const;
  float backgroundPressure() const;  // Pa
  size_t fill(const Vec3& min, const Vec3& max, const env::Environment* env, const Vec3& velocity);
  void emit(const env::Environment& env);
  void removeDead();
  void buildGrid();
  void regrid();
  void scatterGrid();
  void collectPlants(std::span<const models::AirBodies> bodies);
  void plantSide(std::span<models::AirCoupling* const> systems, std::span<const models::AirBodies> bodies);
  void substep(const env::Environment& env, float dt);
  void substepPositionBased(const env::Environment& env, float dt);
  void move(const env::Environment& env, float dt, bool accelerate);
  void querySdf(const env::Environment& env, size_t i);
  size_t addParticle(const Vec3& x, const Vec3& v);

  SphSettings settings_;
  std::vector<SphEmitter> emitters_;
  std::vector<double> emitterClock_;  // s of emission owed per emitter
  float mass_ = 0, h_ = 0;
  float pbfEps_ = 0, pbfCorr_ = 0, pbfInvWq_ = 0;  // the position-based solver's constants (constructor)
  float time_ = 0;
  uint64_t steps_ = 0;
  bool warnedCapacity_ = false, warnedSubsteps_ = false;
  uint64_t sdfRevision_ = 0;  // the environment's obstacleRevision() the distances below are for (0: none)
  SphTimings timings_;

  // Particles, dense, in spawn order.
  std::vector<Vec3> x_, v_;
  std::vector<float> rho_;
  std::vector<float> p_;          // Pa: the position-based solver's pressure from the last substep
  std::vector<float> sdfBudget_;  // lower bound of the distance to any obstacle (m)
  std::vector<float> sdf_;        // distance to the nearest obstacle when closer than h, else +inf
  std::vector<Vec3> sdfNormal_;
  std::vector<uint8_t> dead_;

  std::unique_ptr<Grid> grid_;
  std::unique_ptr<Plants> plants_;
  std::unique_ptr<Walls> walls_;
};

// Building blocks of the air's neighbour search, exposed for their tests.
namespace detail {

// The cells first..last of a row of `cells` cells along one axis (cell c spans origin + c·edge
// to origin + (c + 1)·edge; the outermost reach to infinity) that hold every point p with
// |p − x| < halfWidth, where a point's cell is clamp(⌊(p − origin) / edge⌋) as the grid bins it.
struct CellSpan {
  uint32_t first = 0, last = 0;
};
CellSpan rowCells(float x, float halfWidth, float origin, float edge, int cells);

// Compress-store: writes base + l for every lane l set in the 4-bit mask, in lane order, to
// out[0], out[1], …, and returns how many. Always writes four entries: the ones past the count
// are scratch, so out needs room for four.
uint32_t appendLanes(unsigned mask, uint32_t base, uint32_t* out);

// The air's passes are compiled twice, for the baseline instruction set and for AVX2, and the
// AVX2 ones run where the CPU has it; both give bit-identical results. Whether the AVX2 ones
// run now, and a switch that keeps to the baseline ones (process-wide, for tests).
bool avx2Kernels();
void forceBaselineKernels(bool on);

}  // namespace detail

}  // namespace tendril::wind
