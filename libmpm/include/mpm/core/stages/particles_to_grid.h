#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! P2G: node mass and momentum from particles (APIC or PIC/FLIP).
template <int dim>
class ParticlesToGrid final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "p2g"; }
  std::vector<std::string> reads() const override {
    return {"particle.order", "grid.blocks", "particle.x", "particle.v", "particle.C", "particle.mass"};
  }
  std::vector<std::string> writes() const override { return {"grid.mass", "grid.momentum"}; }
  void run(MpmState<dim>& s) override;
};

}  // namespace mpm::stages
