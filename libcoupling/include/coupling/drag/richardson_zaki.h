#pragma once
//! Hindered drag built to reproduce Richardson & Zaki (1954): the Schiller-Naumann drag of a
//! single sphere times the voidage function n_w^(2 - n),
//!   beta = (3/4) (mu n_s / d^2) Cd Re n_w^(2 - n),   Re = n_w rho_w u d / mu,
//! which is the Wen & Yu (1966) form (gidaspow.h, n = 4.65) over every volume fraction, without
//! Gidaspow's switch to Ergun. Why n_w^(2 - n): a closed column settles at
//! v_s = n_w^2 n_s (rho_s - rho_w) g / beta (docs/coupling.md), so as Re -> 0 (Cd Re -> 24)
//! this law settles at n_w^n v_Stokes, the Richardson-Zaki law with exponent n, at every
//! volume fraction. The exponent is the scene's `drag.exponent`: 4.65 (their low-Re, wide-
//! column value) by default; their correlation lowers it to 4.45 Re_t^-0.1 for terminal
//! Reynolds numbers 1 - 500 and 2.39 above (data/reference/richardson_zaki1954.md).
#include <coupling/drag/drag_parameters.h>
#include <coupling/drag/schiller_naumann.h>

#include <cmath>
#include <string_view>

namespace coupling::drag {

//! Richardson & Zaki's exponent n of v / v_t = n_w^n from their correlation with the terminal
//! Reynolds number Re_t = rho_w v_t d / mu of one grain, in the wide-column limit d / D -> 0
//! (data/reference/richardson_zaki1954.md; the published fit is discontinuous at its bounds).
inline double richardson_zaki_exponent(double terminal_reynolds) {
  const double Re = terminal_reynolds;
  if (Re < 0.2) return 4.65;
  if (Re < 1.0) return 4.35 * std::pow(Re, -0.03);
  if (Re < 500.0) return 4.45 * std::pow(Re, -0.1);
  return 2.39;
}

struct RichardsonZaki {
  static constexpr std::string_view name = "richardson_zaki";
  static constexpr double low_reynolds_exponent = 4.65;  //!< n for Re_t < 0.2, d / D -> 0
  DragParameters p;
  double exponent = low_reynolds_exponent;  //!< n [-], in [2, 6]

  //! beta [kg/(m^3 s)] at fluid fraction n_w in (0, 1] and slip speed u [m/s].
  double beta(double n_w, double slip) const {
    return SchillerNaumann{p}.beta(n_w, slip) * std::pow(n_w, 2.0 - exponent);
  }
};

}  // namespace coupling::drag
