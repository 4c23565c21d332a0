#pragma once
//! The Runner of the coupled state (mpm/core/runner.h): the output folder of a coupled app
//! holds fluid_NNNN.h5 + fluid.xdmf and sediment_NNNN.h5 + sediment.xdmf (the phases present),
//! one preview with the grains over the fluid, diagnostics summed over the phases with a
//! mass_<phase> column each, the columns of the stages (pressure_iterations, pressure_residual,
//! pressure_round_off, inflow_mass_<phase>, outflow_mass_<phase>, ...), and checkpoints of both
//! phases for --restart.
#include <coupling/coupled_state.h>
#include <mpm/core/runner.h>

namespace coupling {

template <int dim>
using CoupledRunner = mpm::Runner<dim, CoupledState<dim>>;

}  // namespace coupling
