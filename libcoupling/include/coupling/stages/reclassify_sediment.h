#pragma once
//! Continuum <-> discrete switching of the sediment particles (docs/coupling.md, "Continuum/discrete
//! switching"). A sediment particle is either part of the granular continuum
//! (Drucker-Prager stress, deformation update, return map) or a discrete grain that carries no
//! stress and moves by gravity, buoyancy and drag alone. Each step, after G2P, the local
//! sediment fraction at the particle,
//!   phi_p = sum_i w_ip n_s,i,
//! decides with hysteresis (phi_low < phi_high):
//!   continuum -> discrete when phi_p < phi_low,   discrete -> continuum when phi_p > phi_high,
//! otherwise the particle keeps its state. In a scene with a bed-load closure (coupling/bed_load.h)
//! the grains the closure carries are bed load, and a grain leaves the continuum only where the
//! current can also suspend it: where its column's wall stress tau_b = rho_w u_*^2 gives a Rouse
//! number w_s / (kappa u_*) below SedimentSwitching::rouse_number (w_s the drag law's settling
//! speed of one grain). Without that, the surface grains that the drift thins below phi_low
//! would turn discrete and the drag would suspend them whatever their size (docs/coupling.md,
//! "What digs the 5 mm hole"). n_s,i is the coupled step's node fraction
//! (VolumeFractionStage) in a wet scene and m_s,i / (rho_s dx^dim) in a dry one (the same
//! estimate without the liquid, volume_fraction.h). Both count the grain volume m_p / rho_s,
//! which the switch never changes. A discrete particle holds the material index
//! mpm::stress_free_material and F^E = I, plastic state 0; a particle that turns continuum
//! starts there, stress-free, so a bed that deposits as discrete grains does not expand when
//! it turns continuum (a bed that kept the compression of an earlier continuum life would).
//! Defaults: docs/coupling.md, "Continuum/discrete switching".
#include <coupling/coupled_state.h>
#include <mpm/core/stage.h>
#include <mpm/solid/stages/stress_free_material.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace coupling {

//! Material index of a discrete sediment grain (no stress).
inline constexpr std::uint16_t discrete_grain = mpm::stress_free_material;

//! The hysteresis band on phi_p [-], scene keys
//!   sediment:
//!     switching: {dilute_below: 0.2, dense_above: 0.45}   # 0 < dilute_below < dense_above < 1
//!     # with bed_load also rouse_number: 2.5                  # > 0
struct SedimentSwitching {
  //! phi_low: below the estimate at the edges of a resting dense bed (a corner particle of a
  //! 2D bed at phi = 0.62 sees 0.37 phi = 0.23), so a bed at rest never flickers, and above
  //! the share of an isolated grain's own volume (about 0.1 phi in 2D, 0.03 phi in 3D).
  double dilute_below = 0.2;
  //! phi_high: below the interior of a settled bed (random loose packing 0.55 and denser) and
  //! above its top particle row, which sees one side only (about 0.6 phi, 0.33 at phi = 0.55):
  //! a deposited grain joins the continuum once another row covers it.
  double dense_above = 0.45;
  //! P_c: the Rouse number below which a column's current suspends its grains (scenes with a
  //! bed-load closure only). 2.5 is the usual bound between bed load and suspended load (the
  //! Rouse profile's exponent, Rouse 1937; bed load above 2.5, half suspended at 1.2-2.5, e.g.
  //! Whipple 2004, MIT 12.163 notes "Essentials of Sediment Transport"); u_* = w_s at P = 2.5,
  //! Bagnold's (1966) criterion for suspension.
  double rouse_number = 2.5;
};

struct SedimentCounts {
  mpm::Index continuum = 0;  //!< sediment particles with a listed material (stressed)
  mpm::Index discrete = 0;   //!< discrete grains (material index discrete_grain)
};

//! The current split of the sediment particles (0, 0 without sediment).
template <int dim>
SedimentCounts count_sediment(const CoupledState<dim>& s);

namespace stages {

//! The switch of the header comment. The continuum particles hold material `continuum`.
//! `suspending_stress` [Pa]: with a bed-load closure, the wall stress rho_w (w_s / (kappa P_c))^2
//! that a grain's column (CoupledState::bed) must reach for the grain to turn discrete;
//! nullopt without one.
template <int dim>
class ReclassifySediment final : public mpm::Stage<CoupledState<dim>> {
public:
  ReclassifySediment(SedimentSwitching thresholds, double sediment_density, std::uint16_t continuum, bool wet,
                     std::optional<double> suspending_stress = std::nullopt);
  std::string name() const override { return "reclassify"; }
  std::vector<std::string> reads() const override;
  std::vector<std::string> writes() const override {
    return {"sediment.particle.material", "sediment.particle.F", "sediment.particle.plastic"};
  }
  void run(CoupledState<dim>& s) override;
  //! With a bed-load closure: `grains_held_as_bed_load`, held_as_bed_load() of the last step.
  std::vector<mpm::Diagnostic> diagnostics() const override;

  //! phi_p of every sediment particle at the last run [-].
  const std::vector<double>& particle_fraction() const { return phi_p_; }
  //! Continuum particles below phi_low that stayed continuum in the last run because their
  //! column's current cannot suspend them.
  mpm::Index held_as_bed_load() const { return held_; }
  //! Particles switched by the last run.
  mpm::Index to_discrete() const { return to_discrete_; }
  mpm::Index to_continuum() const { return to_continuum_; }

private:
  SedimentSwitching thresholds_;
  double rho_s_;
  std::uint16_t continuum_;
  bool wet_;
  std::optional<double> suspending_stress_;
  std::vector<double> dry_fraction_;  // m_s,i / (rho_s dx^dim) per sediment node (dry scene)
  std::vector<double> phi_p_;
  mpm::Index to_discrete_ = 0, to_continuum_ = 0, held_ = 0;
};

}  // namespace stages
}  // namespace coupling
