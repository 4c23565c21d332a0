#pragma once
//! The state of the coupled sediment-fluid step (docs/coupling.md, "The coupled step"): one MpmState
//! per phase, each with its own particles and sparse grid over the same lattice (same origin,
//! dx and extent, so node k of one grid and the node with the same coordinate of the other
//! coincide), plus the volume fractions and the shared clock.
#include <coupling/bed_load.h>
#include <coupling/volume_fraction.h>
#include <mpm/core/state.h>
#include <mpm/core/types.h>

#include <vector>

namespace coupling {

template <int dim>
struct CoupledState {
  mpm::MpmState<dim> fluid;     //!< the liquid (fluid particles carry m_p = n_w rho_w V_p)
  mpm::MpmState<dim> sediment;  //!< the grains (m_p = rho_s V_p, V_p the grain volume)
  bool has_fluid = false;       //!< false: dry scene, `fluid` holds no grid
  bool has_sediment = false;    //!< false: clear fluid, `sediment` holds no grid
  //! n_s and n_w per storage node of the sediment grid (written every step by the fractions stage).
  VolumeFractions fractions;
  //! The drag coefficient beta [kg/(m^3 s)] per storage node of the sediment grid, evaluated
  //! once per step by the exchange stage from the slip entering it (0 where a phase is
  //! missing); the mixture projection uses the same, so that the step's steady state is the
  //! drag law's for any dt.
  std::vector<double> drag;
  //! The bed-surface layer of the bed-load closure (coupling/bed_load.h), rebuilt every step;
  //! empty in a scene without `bed_load`.
  BedLayer<dim> bed;
  double time = 0.0;        //!< [s]
  double dt = 0.0;          //!< step being taken [s]
  double dt_limit = 1e300;  //!< largest step allowed now (frame end) [s]
  mpm::Index step = 0;
};

//! The phases present, fluid first (mpm::PhaseRef): the Runner writes fluid_NNNN.h5 and
//! sediment_NNNN.h5 and draws the fluid as a tint beneath the coloured grains.
template <int dim>
std::vector<mpm::PhaseRef<dim>> phases(CoupledState<dim>& s) {
  std::vector<mpm::PhaseRef<dim>> out;
  if (s.has_fluid)
    out.push_back({"fluid", &s.fluid.particles, {&s.fluid.grid}, !s.has_sediment, mpm::index_bytes(s.fluid)});
  if (s.has_sediment)
    out.push_back({"sediment", &s.sediment.particles, {&s.sediment.grid}, true, mpm::index_bytes(s.sediment)});
  return out;
}

}  // namespace coupling
