#pragma once
//! The drag between the phases, implicit per shared node (docs/coupling.md, "Implicit momentum exchange").
#include <coupling/coupled_state.h>
#include <coupling/momentum_exchange.h>
#include <mpm/core/stage.h>

#include <string>
#include <vector>

namespace coupling::stages {

//! The implicit drag exchange of momentum_exchange.h on the shared nodes.
template <int dim>
class ExchangeStage final : public mpm::Stage<CoupledState<dim>> {
public:
  explicit ExchangeStage(drag::DragLaw law) : exchange_(law) {}
  std::string name() const override { return "exchange"; }
  std::vector<std::string> reads() const override {
    return {"fractions", "fluid.grid.velocity", "sediment.grid.velocity"};
  }
  std::vector<std::string> writes() const override { return {"fluid.grid.velocity", "sediment.grid.velocity", "drag"}; }
  void run(CoupledState<dim>& s) override {
    exchange_.apply(s.fluid.grid, s.sediment.grid, s.fractions.fluid, s.dt, s.drag);
  }

private:
  MomentumExchange<dim> exchange_;
};

}  // namespace coupling::stages
