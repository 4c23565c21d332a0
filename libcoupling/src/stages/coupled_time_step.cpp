#include <coupling/stages/coupled_time_step.h>

#include <algorithm>

namespace coupling::stages {

template <int dim>
void CoupledTimeStep<dim>::run(CoupledState<dim>& s) {
  double dt = s.dt_limit;
  if (s.has_fluid) dt = std::min(dt, fluid_.stable_dt(s.fluid));
  if (s.has_sediment) dt = std::min(dt, sediment_.stable_dt(s.sediment));
  s.dt = dt;
  for (mpm::MpmState<dim>* phase : {&s.fluid, &s.sediment}) {
    phase->time = s.time;
    phase->dt = dt;
    phase->dt_limit = s.dt_limit;
    phase->step = s.step;
  }
}

template class CoupledTimeStep<2>;
template class CoupledTimeStep<3>;

}  // namespace coupling::stages
