#pragma once
//! The time step of the coupled state: the smallest stable step of the phases present.
#include <coupling/coupled_state.h>
#include <mpm/core/stage.h>
#include <mpm/core/stages/time_step_control.h>

#include <string>
#include <vector>

namespace coupling::stages {

//! dt = min over the phases present of their stable step (particle CFL, wave speed: the
//! free-fall limit of the fluid, the elastic wave of a continuum sediment), clipped to the
//! frame end; copies time, dt and step into both phase states.
template <int dim>
class CoupledTimeStep final : public mpm::Stage<CoupledState<dim>> {
public:
  using Settings = typename mpm::stages::TimeStepControl<dim>::Settings;
  CoupledTimeStep(Settings fluid, Settings sediment) : fluid_(fluid), sediment_(sediment) {}
  std::string name() const override { return "time_step"; }
  std::vector<std::string> reads() const override { return {}; }
  std::vector<std::string> writes() const override { return {"dt"}; }
  void run(CoupledState<dim>& s) override;

private:
  mpm::stages::TimeStepControl<dim> fluid_, sediment_;
};

}  // namespace coupling::stages
