#pragma once
//! The liquid's pressure at a point of a coupled scene, whichever fluid solver it runs: a
//! sensor for the apps (the submerged collapse's base pore pressure).
#include <coupling/coupled_scene.h>
#include <coupling/coupled_state.h>
#include <mpm/core/pipeline.h>

#include <functional>

namespace coupling {

//! p(state, x) [Pa]: with the mixture projection its cell pressure at x
//! (PressureProjection::pressure_at); for a weakly compressible liquid the mean pressure
//! of its particles within half a cell of x (NaN where none is). An empty function otherwise
//! (no liquid, or a clear liquid without sediment). The pipeline must outlive the probe.
template <int dim>
using PressureProbe = std::function<double(const CoupledState<dim>&, const mpm::Vec<dim>&)>;

template <int dim>
PressureProbe<dim> liquid_pressure_probe(const CoupledScene<dim>& scene, mpm::Pipeline<CoupledState<dim>>& pipeline);

}  // namespace coupling
