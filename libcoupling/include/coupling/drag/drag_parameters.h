#pragma once
//! What every drag law needs besides the local state: the grain and the fluid (SI units).
//!
//! Conventions shared by all laws (docs/coupling.md):
//!  * beta [kg/(m^3 s)] is the momentum-exchange coefficient per unit mixture volume: the drag
//!    force density on the sediment is beta (v_w - v_s), on the fluid beta (v_s - v_w)
//!    (the LANS equations).
//!  * u = |v_s - v_w| is the slip speed between the phase (interstitial) velocities [m/s].
//!  * Re = n_w rho_w u d / mu, the grain Reynolds number of the superficial slip velocity
//!    n_w u, as in Wen & Yu (1966) and Gidaspow (1994, ch. 5) and Di Felice (1994).
//!  * Laws built on a single-sphere drag coefficient are written with Cd Re (finite as
//!    Re -> 0) rather than Cd, so that beta stays finite and exact at zero slip:
//!      beta = (3/4) Cd n_s n_w rho_w u / d = (3/4) (mu n_s / d^2) Cd Re.
#include <cmath>

namespace coupling::drag {

struct DragParameters {
  double diameter = 0.0;   //!< grain diameter d [m] > 0
  double viscosity = 0.0;  //!< fluid dynamic viscosity mu [Pa s] > 0
  double density = 0.0;    //!< fluid density rho_w [kg/m^3] > 0

  //! Re = n_w rho_w u d / mu [-] for fluid fraction n_w and slip speed u [m/s].
  double reynolds(double n_w, double slip) const { return n_w * density * slip * diameter / viscosity; }
  //! (3/4) mu / d^2 [kg/(m^3 s)]: beta = stokes_scale() n_s Cd Re (see above).
  double stokes_scale() const { return 0.75 * viscosity / (diameter * diameter); }
  //! Stokes's terminal velocity (rho_s - rho_w) |g| d^2 / (18 mu) [m/s] of one grain of density
  //! rho_s [kg/m^3] under gravity |g| [m/s^2].
  double stokes_velocity(double sediment_density, double gravity) const {
    return (sediment_density - density) * gravity * diameter * diameter / (18.0 * viscosity);
  }
};

}  // namespace coupling::drag
