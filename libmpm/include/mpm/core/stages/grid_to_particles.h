#pragma once
#include <mpm/core/stages/particle_stage.h>

#include <memory>
#include <string>

namespace mpm::stages {

//! G2P and advection: v_p, C_p from the grid; x_p += dt v_p^PIC. Given the name of a matrix
//! channel (the solid's elastic F), also the deformation update F_p = (I + dt grad v_p) F_p of
//! every particle in the same gather (stress-free grains too: their owner resets F, so the loop
//! stays branch-free). Given a particle stage `then` (the return map), each bucket's particles
//! go through it right after their gather: stage "g2p_<then's name>", one pass for both.
template <int dim>
class GridToParticles final : public Stage<MpmState<dim>> {
public:
  explicit GridToParticles(std::string deformation = {}, std::unique_ptr<ParticleStage<dim>> then = nullptr)
      : deformation_(std::move(deformation)), then_(std::move(then)) {}
  std::string name() const override { return then_ ? "g2p_" + then_->name() : "g2p"; }
  std::vector<std::string> reads() const override;
  std::vector<std::string> writes() const override;
  void run(MpmState<dim>& s) override;

private:
  //! The NaN guard over all particles: throws naming the first bad one.
  void check_results(const Particles<dim>& P, const std::vector<Mat<dim>>* F) const;
  std::string deformation_;  // channel updated with the velocity gradient; empty: none
  std::unique_ptr<ParticleStage<dim>> then_;
};

}  // namespace mpm::stages
