#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/solid/material.h>
#include <mpm/solid/solid_channels.h>

namespace mpm::stages {

//! V^0 tau of one particle from its Kirchhoff stress tau, scaled by the plasticity's hardening
//! of the particle's plastic state.
template <int dim, class Plasticity>
Mat<dim> weighted_kirchhoff(const Plasticity& plasticity, double volume0, const Mat<dim>& tau, double plastic) {
  return volume0 * plasticity.modulus_scale(plastic) * tau;
}

//! The same for a material (model, plasticity) from the SVD f of F^E:
//! tau = P(F^E) F^E^T = U diag(p_i sigma_i) U^T.
template <int dim, class Elastic, class Plasticity>
Mat<dim> weighted_kirchhoff(const Elastic& model, const Plasticity& plasticity, double volume0, const math::Svd<dim>& f,
                            double plastic) {
  return weighted_kirchhoff(plasticity, volume0, constitutive::isotropic_kirchhoff(model, f), plastic);
}

//! The same from F^E; the return map's cached tau instead where `cached` points at a known one
//! (solid_channels.h).
template <int dim, class Elastic, class Plasticity>
Mat<dim> weighted_kirchhoff(const Elastic& model, const Plasticity& plasticity, double volume0, const Mat<dim>& F,
                            double plastic, const Mat<dim>* cached) {
  if (cached && solid::known_stress(*cached)) return weighted_kirchhoff(plasticity, volume0, *cached, plastic);
  return weighted_kirchhoff(model, plasticity, volume0, math::svd(F), plastic);
}

//! Internal elastic forces on grid nodes from the particles' Kirchhoff stress. A scene whose
//! particles may carry an index outside the material list (stress_free_material: discrete
//! grains) says so with `stress_free_particles`; those particles then add no force. Without it
//! every particle must hold a listed material and the loop is that of a plain solid.
//! With Scatter::with_momentum the stage is also the step's p2g: node mass, momentum and
//! forces in one pass over particles and grid (stage "p2g_stress", on a uniform or adaptive
//! grid); unless the scheme is FLIP (which keeps the velocity before the forces), the forces
//! go into the momentum as the impulse dt f and grid.force is released (transfer.h).
template <int dim>
class StressForces final : public Stage<MpmState<dim>> {
public:
  enum class Scatter { forces, with_momentum };
  explicit StressForces(std::vector<Material<dim>> materials, bool stress_free_particles = false,
                        Scatter scatter = Scatter::forces)
      : materials_(std::move(materials)), stress_free_particles_(stress_free_particles), scatter_(scatter) {}
  std::string name() const override { return fused() ? "p2g_stress" : "stress_forces"; }
  std::vector<std::string> reads() const override {
    std::vector<std::string> r{"particle.order",    "grid.blocks", "particle.x",      "particle.volume0",
                               "particle.material", "particle.F",  "particle.plastic"};
    if (fused()) r.insert(r.end(), {"particle.v", "particle.C", "particle.mass"});
    return r;
  }
  std::vector<std::string> writes() const override {
    if (fused()) return {"grid.mass", "grid.momentum", "grid.force"};
    return {"grid.force"};
  }
  void run(MpmState<dim>& s) override;

private:
  bool fused() const { return scatter_ == Scatter::with_momentum; }
  std::vector<Material<dim>> materials_;
  bool stress_free_particles_;
  Scatter scatter_;
  std::vector<Mat<dim>> weighted_stress_;  // V_p^0 tau_p per particle [N m], unless read from the cache
  std::vector<double> stress_weight_;      // V_p^0 times the modulus scale, with the cache where it varies
};

}  // namespace mpm::stages
