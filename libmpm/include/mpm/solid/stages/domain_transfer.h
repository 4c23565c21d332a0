#pragma once
//! The transfers of a scene with particle domains (mpm/domains/particle_domains.h): they take the
//! place of sort -> p2g -> stress_forces and of deformation -> g2p in the explicit step,
//!   time_step -> domains_to_grid -> grid_update -> boundary -> domains_from_grid.
//! Elastic materials only (a return map would need F^E apart from the corners' F).
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/solid/material.h>

namespace mpm::stages {

//! Corner masses, momenta and forces f_alpha = - sum_p V_p^0 P(F_p) grad_X w_alpha_p (eq. 8),
//! scattered to the grid from the corners.
template <int dim>
class DomainsToGrid final : public Stage<MpmState<dim>> {
public:
  explicit DomainsToGrid(std::vector<Material<dim>> materials) : materials_(std::move(materials)) {}
  std::string name() const override { return "domains_to_grid"; }
  std::vector<std::string> reads() const override {
    return {"particle.v", "particle.mass", "particle.volume0", "particle.material", "particle.F"};
  }
  std::vector<std::string> writes() const override {
    return {"grid.blocks", "grid.mass", "grid.momentum", "grid.force"};
  }
  void run(MpmState<dim>& s) override;

private:
  std::vector<Material<dim>> materials_;
  std::vector<Mat<dim>> weighted_stress_;  // V_p^0 P_p per particle [N m]
};

//! Corner velocities and positions from the grid (eq. 9), then per particle the PIC/FLIP
//! velocity, x_p as the mean of its corners and F_p from them (eq. 7).
template <int dim>
class DomainsFromGrid final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "domains_from_grid"; }
  std::vector<std::string> reads() const override { return {"grid.velocity", "particle.v"}; }
  std::vector<std::string> writes() const override { return {"particle.x", "particle.v", "particle.F"}; }
  void run(MpmState<dim>& s) override;
};

}  // namespace mpm::stages
