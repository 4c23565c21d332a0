#pragma once
//! Gidaspow (1994, Multiphase Flow and Fluidization, eqs. 5.65 and 5.67): the Ergun (1952)
//! packed-bed law in dense regions and Wen & Yu (1966) in dilute ones,
//!   n_w <  0.8:  beta = 150 n_s^2 mu / (n_w d^2) + 1.75 n_s rho_w u / d          (Ergun)
//!   n_w >= 0.8:  beta = (3/4) Cd n_s n_w rho_w u / d n_w^-2.65                    (Wen-Yu)
//!                     = SchillerNaumann beta * n_w^-2.65,   Re = n_w rho_w u d / mu.
//! The published switch is discontinuous at n_w = 0.8 (Ergun is 15 % above Wen-Yu there at
//! Re -> 0); kept as published. The Wen-Yu branch implies hindered settling with the
//! Richardson-Zaki exponent 4.65 at low Re (docs/coupling.md).
#include <coupling/drag/drag_parameters.h>
#include <coupling/drag/schiller_naumann.h>

#include <cmath>
#include <string_view>

namespace coupling::drag {

struct Gidaspow {
  static constexpr std::string_view name = "gidaspow";
  static constexpr double switch_fraction = 0.8;  //!< n_w below which Ergun applies
  DragParameters p;

  //! beta [kg/(m^3 s)] at fluid fraction n_w in (0, 1] and slip speed u [m/s].
  double beta(double n_w, double slip) const {
    const double n_s = 1.0 - n_w;
    if (n_w < switch_fraction)
      return 150.0 * n_s * n_s * p.viscosity / (n_w * p.diameter * p.diameter) +
             1.75 * n_s * p.density * slip / p.diameter;
    return SchillerNaumann{p}.beta(n_w, slip) * std::pow(n_w, -2.65);
  }
};

}  // namespace coupling::drag
