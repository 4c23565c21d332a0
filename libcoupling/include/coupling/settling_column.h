#pragma once
//! The settling column (issue 4; docs/coupling.md, "Settling"): a uniform suspension of one
//! grain size at volume fraction phi in the lower part of a closed column of fluid. The
//! grains are discrete (no stress: gravity, buoyancy and drag only). Shared by the `settling`
//! app and the coupled verification tests, which build the same scene from a scene file:
//!
//!   column:
//!     width: 0.008              # [m]
//!     height: 0.03              # fluid depth [m]
//!     suspension_height: 0.02   # the suspension fills 0 <= y <= this [m], <= height
//!     cells_per_width: 8        # dx = width / cells_per_width
//!     particles_per_cell: 4     # k^dim, each phase
//!   fluid: {density: 1000, viscosity: 1.0e-3}   # rho_w [kg/m^3] > 0, mu [Pa s] > 0
//!   sediment:
//!     density: 2650             # rho_s [kg/m^3] > rho_w
//!     volume_fraction: 0.01     # phi in (0, 1 - n_min)
//!   drag: {law: stokes, grain_diameter: 1.0e-4}   # drag_law.h
//! plus the shared keys (scene_settings.h), pressure (fluid_scene.h) and walls (default
//! sticky on every face; the column is closed).
#include <coupling/coupled_scene.h>
#include <mpm/core/config.h>

namespace coupling {

struct SettlingColumn {
  double width = 0.0, height = 0.0, suspension_height = 0.0;  //!< [m]
  double volume_fraction = 0.0;                               //!< phi [-]
  double fluid_density = 0.0, sediment_density = 0.0;         //!< [kg/m^3]
  drag::DragLaw drag;
  double gravity = 0.0;  //!< |g| [m/s^2]

  //! Stokes terminal velocity of one grain, (rho_s - rho_w) |g| d^2 / (18 mu) [m/s].
  double stokes_velocity() const;
  //! The hindered settling speed the drag law implies in a closed column [m/s], from the steady
  //! sediment balance n_s n_w (rho_s - rho_w) g = beta(n_w, u) u with the fluid's return flow
  //! n_w v_w + n_s v_s = 0, so the slip is u = v_s / n_w (docs/coupling.md): v_s = n_w u, u the
  //! root of beta(n_w, u) u = n_s n_w (rho_s - rho_w) g (bisection; beta u grows with u).
  double hindered_velocity() const;
  //! Terminal velocity of one grain in unbounded fluid with the standard drag curve
  //! (Schiller-Naumann Cd) [m/s]: the root of (3/4) (mu / d^2) Cd Re v = (rho_s - rho_w) g.
  double terminal_velocity() const;
  //! The measured settling speed of Richardson & Zaki (1954), n_w^n v_t, with v_t the terminal
  //! velocity above and n their correlation at Re_t = reynolds(v_t) (drag/richardson_zaki.h) [m/s].
  double richardson_zaki_velocity() const;
  //! Grain Reynolds number rho_w v d / mu of a settling speed v [m/s].
  double reynolds(double velocity) const;
};

template <int dim>
struct SettlingScene {
  SettlingColumn column;
  CoupledScene<dim> scene;
};

//! Reads the keys above and seeds both phases (fluid fraction 1 - phi inside the suspension).
//! InputError (file, line, key, value, range) on a bad value.
template <int dim>
SettlingScene<dim> load_settling_column(const mpm::Config& scene);

//! Mean vertical velocity [m/s] (negative: down) of the sediment particles higher than
//! `floor_margin` [m] (those not yet in the deposit), over the whole width: a circulation of
//! the mixture carries no net volume through a horizontal section, so this is the settling
//! velocity of the suspension even where the walls drive one.
template <int dim>
double mean_sediment_velocity(const CoupledState<dim>& state, double floor_margin);

//! Height of the upper edge of the suspension [m]: the highest sediment particle farther than
//! `wall_margin` [m] from the side walls (the walls hold back the grains next to them).
template <int dim>
double suspension_top(const CoupledState<dim>& state, const SettlingColumn& column, double wall_margin);

}  // namespace coupling
