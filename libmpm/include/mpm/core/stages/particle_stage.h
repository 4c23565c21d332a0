#pragma once
//! A stage that updates each particle from that particle's own state (a return map). It runs
//! on its own over all particles, or inside another pass right after that pass has touched a
//! group of particles (GridToParticles hands it each bucket right after the bucket's gather),
//! while their channels are still in cache: one pass over the particles instead of two.
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/core/transfer.h>

namespace mpm::stages {

template <int dim>
class ParticleStage : public Stage<MpmState<dim>> {
public:
  //! The update of this step over `s` (channels looked up once): called on disjoint lists of
  //! particle indices, in parallel; the result of a particle does not depend on its list.
  virtual ParticleGroupUpdate bind(MpmState<dim>& s) = 0;
  //! What follows the update of every particle (the checks of its results).
  virtual void finish(MpmState<dim>& /*s*/) {}
  //! bind(s) over all particles in parallel, then finish(s).
  void run(MpmState<dim>& s) override;
};

}  // namespace mpm::stages
