#pragma once
//! Schiller & Naumann (1933) drag of a single sphere, Re = n_w rho_w u d / mu:
//!   Cd = 24/Re (1 + 0.15 Re^0.687)  for Re < 1000,   Cd = 0.44 above,
//! applied to the grains of the mixture without a hindrance (voidage) function:
//!   beta = (3/4) Cd n_s n_w rho_w u / d = (3/4) (mu n_s / d^2) Cd Re.
//! This is the Wen & Yu (1966) coefficient without its n_w^-2.65 (gidaspow.h). As Re -> 0,
//! Cd Re -> 24 and beta -> 18 mu n_s / d^2, the Stokes law (stokes.h). Cd jumps by 0.4 % at
//! Re = 1000 (the published fit: 0.4383 below, 0.44 above).
#include <coupling/drag/drag_parameters.h>

#include <cmath>
#include <string_view>

namespace coupling::drag {

//! Cd Re of the Schiller-Naumann fit [-], finite for Re >= 0.
inline double schiller_naumann_cd_re(double Re) {
  return Re < 1000.0 ? 24.0 * (1.0 + 0.15 * std::pow(Re, 0.687)) : 0.44 * Re;
}

struct SchillerNaumann {
  static constexpr std::string_view name = "schiller_naumann";
  DragParameters p;

  //! beta [kg/(m^3 s)] at fluid fraction n_w in (0, 1] and slip speed u [m/s].
  double beta(double n_w, double slip) const {
    return p.stokes_scale() * (1.0 - n_w) * schiller_naumann_cd_re(p.reynolds(n_w, slip));
  }
};

}  // namespace coupling::drag
