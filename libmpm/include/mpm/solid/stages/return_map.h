#pragma once
#include <mpm/core/stages/particle_stage.h>
#include <mpm/solid/material.h>

#include <atomic>

namespace mpm::stages {

//! Projects the trial elastic deformation of plastic materials back onto their yield surface.
//! A scene whose materials are all elastic does not add this stage. Particles of an index
//! outside the list (stress_free_material) are left alone. A particle stage: the solvers hand
//! it to g2p, which projects each bucket right after its gather (stage "g2p_plasticity").
template <int dim>
class ReturnMap final : public ParticleStage<dim> {
public:
  explicit ReturnMap(std::vector<Material<dim>> materials) : materials_(std::move(materials)) {}
  std::string name() const override { return "plasticity"; }
  std::vector<std::string> reads() const override { return {"particle.F", "particle.plastic", "particle.material"}; }
  std::vector<std::string> writes() const override { return {"particle.F", "particle.plastic"}; }
  // (and particle.rest_packing of dilatant materials: a channel only they carry)
  ParticleGroupUpdate bind(MpmState<dim>& s) override;
  void finish(MpmState<dim>& s) override;

private:
  std::vector<Material<dim>> materials_;
  std::atomic<bool> finite_{true};  // every F^E mapped since bind() finite
};

//! True when some material has a plasticity model other than none.
template <int dim>
bool any_plastic(const std::vector<Material<dim>>& materials);

//! True when some material is a dilatant Drucker-Prager sand (its particles need a packing).
template <int dim>
bool any_dilatant(const std::vector<Material<dim>>& materials);

}  // namespace mpm::stages
