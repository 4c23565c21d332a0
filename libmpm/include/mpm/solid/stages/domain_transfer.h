#pragma once
//! The transfers of a scene with particle domains (mpm/domains/particle_domains.h): they take the
//! place of sort -> p2g -> stress_forces and of g2p (with the deformation update) in the
//! explicit step,
//!   [enrichment ->] time_step -> domains_to_grid -> grid_update -> boundary -> domains_from_grid,
//! and of sort -> p2g and g2p around the implicit update (which solves for the
//! grid and the enriched corners together, implicit_update.h).
//! Bodies with domains are elastic (a return map would need F^E apart from the corners' F);
//! plastic bodies run among them as material points (particle_domains.h), whose return map
//! follows domains_from_grid in the explicit step.
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>
#include <mpm/solid/material.h>

namespace mpm::stages {

//! Dynamic enrichment (Zhu et al. sec. 5, Algorithm 1 line 2): at the start of the step, the
//! corners of every particle with K(F_p) <= epsilon become degrees of freedom of their own
//! (particle_domains.h). First in the step, so the time step sees the enriched domains.
template <int dim>
class DomainEnrichment final : public Stage<MpmState<dim>> {
public:
  //! `explicit_step`: the enriched corners are stepped explicitly (domains_from_grid), which
  //! bounds the time step by the thinnest enriched domain (mark_enrichment).
  explicit DomainEnrichment(bool explicit_step) : explicit_step_(explicit_step) {}
  std::string name() const override { return "enrichment"; }
  std::vector<std::string> reads() const override { return {"particle.F"}; }
  std::vector<std::string> writes() const override { return {"domains.enriched"}; }
  void run(MpmState<dim>& s) override;
  //! enriched_particles: the share of particles with K(F) <= epsilon.
  std::vector<Diagnostic> diagnostics() const override { return {{"enriched_particles", share_}}; }

private:
  bool explicit_step_;
  double share_ = 0.0;
};

//! Corner masses, momenta and forces f_alpha = - sum_p V_p^0 P(F_p) grad_X w_alpha_p (eq. 8),
//! scattered to the grid from the corners; the material points' V^0 tau as in StressForces.
//! Without `forces` (an implicit step, which forms its forces inside the solve) the stress and
//! the corner forces are skipped and grid.force stays zero.
template <int dim>
class DomainsToGrid final : public Stage<MpmState<dim>> {
public:
  explicit DomainsToGrid(std::vector<Material<dim>> materials, bool forces = true)
      : materials_(std::move(materials)), forces_(forces) {}
  std::string name() const override { return "domains_to_grid"; }
  std::vector<std::string> reads() const override {
    return {"particle.v", "particle.mass", "particle.volume0", "particle.material", "particle.F", "particle.plastic"};
  }
  std::vector<std::string> writes() const override {
    return {"grid.blocks", "grid.mass", "grid.momentum", "grid.force"};
  }
  void run(MpmState<dim>& s) override;

private:
  std::vector<Material<dim>> materials_;
  bool forces_;
  std::vector<Mat<dim>> weighted_stress_;  // V_p^0 P_p per particle [N m]
};

//! Corner velocities from the grid (eq. 9), the enriched corners' own update with the
//! colliders, the enriched surfaces' self-contact (domains/surface_contact.h), the corners
//! moved; then per particle the PIC/FLIP velocity, x_p as the mean of its corners and F_p from
//! them (eq. 7), or for a material point F_p = (I + dt grad v_p) F_p.
template <int dim>
class DomainsFromGrid final : public Stage<MpmState<dim>> {
public:
  //! `enriched_stepped`: the grid update (an implicit step) has left the enriched corners' new
  //! velocities in domains.momentum and their increments in domains.force.
  //! `self_contact`: the scene's domains have a contact thickness (reported every step).
  DomainsFromGrid(geometry::ColliderSet<dim> colliders, bool enriched_stepped, bool self_contact)
      : colliders_(std::move(colliders)), enriched_stepped_(enriched_stepped), contacts_(self_contact ? 0 : -1) {}
  std::string name() const override { return "domains_from_grid"; }
  std::vector<std::string> reads() const override { return {"grid.velocity", "particle.v", "particle.F"}; }
  std::vector<std::string> writes() const override { return {"particle.x", "particle.v", "particle.F"}; }
  void run(MpmState<dim>& s) override;
  //! surface_contacts (with domains.contact_thickness > 0): the vertex-face pairs of the enriched
  //! surfaces' self-contact that received an impulse in the step.
  std::vector<Diagnostic> diagnostics() const override {
    if (contacts_ < 0) return {};
    return {{"surface_contacts", static_cast<double>(contacts_)}};
  }

private:
  geometry::ColliderSet<dim> colliders_;  // act on the enriched corners as the boundary stage on nodes
  bool enriched_stepped_;
  long contacts_;  // -1: no self-contact in this scene
};

}  // namespace mpm::stages
