#pragma once
//! The Runner of the coupled state (mpm/core/runner.h): the output folder of a coupled app
//! holds fluid_NNNN.h5 + fluid.xdmf and sediment_NNNN.h5 + sediment.xdmf (the phases present),
//! one preview with the grains over the fluid, diagnostics summed over the phases with a
//! mass_<phase> column each, and checkpoints of both phases for --restart.
#include <coupling/coupled_state.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/runner.h>

namespace coupling {

template <int dim>
using CoupledRunner = mpm::Runner<dim, CoupledState<dim>>;

//! Adds the columns pressure_iterations, pressure_residual and pressure_round_off of the pipeline's pressure stage
//! (the mixture projection, or the fluid's own in a clear-fluid scene); InputError when the
//! pipeline has none (a dry scene).
template <int dim>
void add_pressure_columns(CoupledRunner<dim>& runner, mpm::Pipeline<CoupledState<dim>>& pipeline);

//! Adds inflow_mass_<phase> (emitted by its sources since the start) and outflow_mass_<phase>
//! (removed by its sinks since the start) [kg] for the fluid and the sediment.
template <int dim>
void add_flow_columns(CoupledRunner<dim>& runner, mpm::Pipeline<CoupledState<dim>>& pipeline);

}  // namespace coupling
