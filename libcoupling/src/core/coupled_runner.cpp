#include <coupling/coupled_runner.h>
#include <coupling/stages/coupled_stages.h>
#include <coupling/stages/on_phase.h>
#include <mpm/core/detail/runner_impl.h>
#include <mpm/core/stages/particle_sink.h>
#include <mpm/core/stages/particle_source.h>

#include <string>
#include <vector>

namespace coupling {

template <int dim>
void add_pressure_columns(CoupledRunner<dim>& runner, mpm::Pipeline<CoupledState<dim>>& pipeline) {
  const fluid::stages::PressureProjection<dim>* projection = nullptr;
  if (const auto* mixture = pipeline.template find<stages::MixtureProjection<dim>>())
    projection = &mixture->projection();
  for (stages::OnPhase<dim>* on : pipeline.template find_all<stages::OnPhase<dim>>())
    if (const auto* own = dynamic_cast<const fluid::stages::PressureProjection<dim>*>(&on->stage()))
      projection = own;
  if (!projection) throw mpm::InputError("add_pressure_columns: the coupled pipeline has no pressure stage");
  runner.add_column("pressure_iterations",
                    [projection](const CoupledState<dim>&) { return double(projection->last_result().iterations); });
  runner.add_column("pressure_residual",
                    [projection](const CoupledState<dim>&) { return projection->last_result().relative_residual; });
  runner.add_column("pressure_round_off",
                    [projection](const CoupledState<dim>&) { return projection->stopped_at_round_off() ? 1.0 : 0.0; });
}

template <int dim>
void add_flow_columns(CoupledRunner<dim>& runner, mpm::Pipeline<CoupledState<dim>>& pipeline) {
  for (const stages::Phase phase : {stages::Phase::fluid, stages::Phase::sediment}) {
    std::vector<const mpm::stages::ParticleSource<dim>*> sources;
    std::vector<const mpm::stages::ParticleSink<dim>*> sinks;
    for (stages::OnPhase<dim>* on : pipeline.template find_all<stages::OnPhase<dim>>()) {
      if (on->phase() != phase) continue;
      if (const auto* s = dynamic_cast<const mpm::stages::ParticleSource<dim>*>(&on->stage())) sources.push_back(s);
      if (const auto* s = dynamic_cast<const mpm::stages::ParticleSink<dim>*>(&on->stage())) sinks.push_back(s);
    }
    const std::string name = stages::phase_name(phase);
    runner.add_column("inflow_mass_" + name, [sources](const CoupledState<dim>&) {
      double m = 0.0;
      for (const auto* s : sources) m += s->emitted_mass();
      return m;
    });
    runner.add_column("outflow_mass_" + name, [sinks](const CoupledState<dim>&) {
      double m = 0.0;
      for (const auto* s : sinks) m += s->removed_mass();
      return m;
    });
  }
}

template void add_pressure_columns(CoupledRunner<2>&, mpm::Pipeline<CoupledState<2>>&);
template void add_flow_columns(CoupledRunner<2>&, mpm::Pipeline<CoupledState<2>>&);
template void add_flow_columns(CoupledRunner<3>&, mpm::Pipeline<CoupledState<3>>&);
template void add_pressure_columns(CoupledRunner<3>&, mpm::Pipeline<CoupledState<3>>&);

}  // namespace coupling

namespace mpm {

template class Runner<2, coupling::CoupledState<2>>;
template class Runner<3, coupling::CoupledState<3>>;

}  // namespace mpm
