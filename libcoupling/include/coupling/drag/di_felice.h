#pragma once
//! Di Felice (1994), "The voidage function for fluid-particle interaction systems",
//! Int. J. Multiphase Flow 20(1):153-159. The drag on a grain in a suspension is the drag of
//! an isolated grain at the same superficial slip velocity n_w u times the voidage function
//! n_w^-chi:
//!   F = Cd (pi d^2 / 8) rho_w (n_w u)^2 n_w^-chi,    Re = n_w rho_w u d / mu,
//!   Cd = (0.63 + 4.8 / sqrt(Re))^2                    (Dallavalle's single-sphere fit),
//!   chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2),
//! the form used in CFD-DEM (Zhou et al. 2010, J. Fluid Mech. 661:482-510, Table 3). With
//! n_s / (pi d^3 / 6) grains per unit volume, beta = F / u per unit volume:
//!   beta = (3/4) Cd rho_w u n_s n_w^(2 - chi) / d = (3/4) (mu n_s / d^2) Cd Re n_w^(1 - chi),
//!   Cd Re = (0.63 sqrt(Re) + 4.8)^2.
//! As Re -> 0: chi -> 3.7 and beta -> 17.28 mu n_s n_w^-2.7 / d^2, which implies hindered
//! settling v_s = n_w^4.7 v_Stokes' (Richardson-Zaki exponent 4.7; docs/coupling.md).
#include <coupling/drag/drag_parameters.h>

#include <cmath>
#include <string_view>

namespace coupling::drag {

//! The voidage exponent chi(Re) [-]; its Re -> 0 limit 3.7 at Re = 0.
inline double di_felice_exponent(double Re) {
  if (Re <= 0.0) return 3.7;
  const double s = 1.5 - std::log10(Re);
  return 3.7 - 0.65 * std::exp(-0.5 * s * s);
}

struct DiFelice {
  static constexpr std::string_view name = "di_felice";
  DragParameters p;

  //! beta [kg/(m^3 s)] at fluid fraction n_w in (0, 1] and slip speed u [m/s].
  double beta(double n_w, double slip) const {
    const double Re = p.reynolds(n_w, slip);
    const double sqrt_cd_re = 0.63 * std::sqrt(Re) + 4.8;
    return p.stokes_scale() * (1.0 - n_w) * sqrt_cd_re * sqrt_cd_re * std::pow(n_w, 1.0 - di_felice_exponent(Re));
  }
};

}  // namespace coupling::drag
