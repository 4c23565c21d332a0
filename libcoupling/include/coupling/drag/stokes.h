#pragma once
//! Stokes drag: each grain feels 3 pi mu d (v_w - v_s), and there are n_s / (pi d^3 / 6)
//! grains per unit mixture volume, so
//!   beta = 18 mu n_s / d^2.
//! No n_w factor: this is the dilute (single-grain) limit, and it is exactly the Re -> 0 limit
//! of SchillerNaumann, whose superficial-velocity Reynolds number (n_w in Re) and n_w prefactor
//! cancel there. In a closed column it implies the hindered settling speed
//! v_s = n_w^2 v_Stokes (docs/coupling.md), which is too fast in dense suspensions; use
//! DiFelice or Gidaspow there.
#include <coupling/drag/drag_parameters.h>

#include <string_view>

namespace coupling::drag {

struct Stokes {
  static constexpr std::string_view name = "stokes";
  DragParameters p;

  //! beta [kg/(m^3 s)] at fluid fraction n_w in (0, 1] and slip speed u [m/s] (unused).
  double beta(double n_w, double /*slip*/) const { return 24.0 * p.stokes_scale() * (1.0 - n_w); }
};

}  // namespace coupling::drag
