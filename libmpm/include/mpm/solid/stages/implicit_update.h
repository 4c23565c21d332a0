#pragma once
#include <mpm/constitutive/detail/isotropic.h>
#include <mpm/core/solve/solve_control.h>
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>
#include <mpm/solid/material.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mpm::stages {

//! The keys of an implicit solid step (scene key `implicit`, docs/user_guide.md).
struct ImplicitSettings {
  //! Newton stops when the mass-weighted rms velocity residual |g|_{M^-1} / sqrt(M) is at most
  //! tolerance * (max(rms(v^*), rms(v)) + |g| dt): a relative accuracy of the step's velocities.
  double tolerance = 1e-5;
  int max_newton_iterations = 50;
  double linear_tolerance = 1e-3;  //!< relative residual of each Newton system (an inexact Newton step)
  int max_linear_iterations = 1000;
  solve::OnFailure on_failure = solve::OnFailure::stop;
};

//! Backward Euler on the grid velocities of an elastoplastic solid (Stomakhin et al. 2013;
//! Zhu et al. sec. 6): Newton's method with a line search on the incremental potential, the
//! systems solved matrix-free by Jacobi-preconditioned CG, walls and colliders enforced in the
//! solve. Replaces stress_forces + grid_update of the explicit step; the same deformation
//! update and return map follow it. With particle domains (s.domains, elastic materials) the
//! particles deform with their domain corners, and the enriched corners are unknowns beside
//! the nodes (Zhu et al. sec. 5-6). Equations in the source file.
//!
//! The unknowns, in every vector below: the grid's node storage, then with enriched particle
//! domains one slot per domain corner; only the enriched corners' slots have mass
//! (unknown_mass).

template <int dim>
class ImplicitUpdate final : public Stage<MpmState<dim>> {
public:
  //! Particles of no listed material (stress-free grains) add no stress.
  ImplicitUpdate(std::vector<Material<dim>> materials, geometry::ColliderSet<dim> colliders, ImplicitSettings settings);
  std::string name() const override { return "implicit_update"; }
  //! grid.blocks stands for the particles' buckets too: sort writes both; with domains,
  //! domains_to_grid writes it with the corners' buckets, which the stage then uses.
  std::vector<std::string> reads() const override {
    return {"grid.blocks",      "grid.mass",         "grid.momentum", "particle.x",
            "particle.volume0", "particle.material", "particle.F",    "particle.plastic"};
  }
  std::vector<std::string> writes() const override { return {"grid.velocity"}; }
  void run(MpmState<dim>& s) override;
  //! newton_iterations, linear_iterations (CG or GMRES, summed over the step's Newton iterations) and
  //! newton_residual (the last step's final relative residual, compare with `tolerance`);
  //! newton_unconverged: steps so far (a restart included) whose Newton solve did not converge
  //! (implicit.on_failure: warn). An app's --check fails when it is not 0.
  std::vector<Diagnostic> diagnostics() const override;
  CarriedData carried() const override { return {{"unconverged", {double(unconverged_)}}}; }
  void restore(const CarriedData& data) override {
    for (const auto& [key, values] : data)
      if (key == "unconverged" && values.size() == 1) unconverged_ = static_cast<std::int64_t>(values[0]);
  }
  //! The line search's merit at the start and after each Newton iteration of the last step:
  //! the incremental potential, or |g|^2_{M^-1} / 2 when a material is plastic.
  const std::vector<double>& merit_history() const { return history_; }

  //! The mass of each unknown [kg]: the grid's nodes, then with enrichment each corner (0 unless
  //! enriched).
  const std::vector<double>& unknown_mass(const MpmState<dim>& s);
  //! The incremental potential E(v) = sum_i m_i |v_i - v_i^*|^2 / 2 + sum_p V_p^0 psi(F_p(v)),
  //! F_p(v) = F_p^n + dt G_p(v) (source file), for the unknown velocities v and predicted
  //! velocities v^*. Public for tests.
  double potential(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, const std::vector<Vec<dim>>& predicted);
  //! Its gradient g = M (v - v^*) - dt f(v) at v, unconstrained.
  void gradient(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, const std::vector<Vec<dim>>& predicted,
                std::vector<Vec<dim>>& g);
  //! The Hessian-vector product (M + dt^2 K) dv at v; with `definite` the stress differential
  //! made positive semi-definite (Teran et al. 2005), as the solve uses it.
  void hessian_product(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, const std::vector<Vec<dim>>& dv,
                       std::vector<Vec<dim>>& out, bool definite);

  //! The Jacobi preconditioner's diagonal of (M + dt^2 K) at v, per unknown and component, with
  //! the stress differential made definite as `definite` asks.
  void preconditioner_diagonal(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, std::vector<Vec<dim>>& out,
                               bool definite);

private:
  struct Outcome {
    int newton_iterations = 0;
    int linear_iterations = 0;
    double residual = 0.0;  //!< relative, as `tolerance`
    bool converged = false;
  };
  //! G_p(v) = dF_p / dt for unknown velocities v.
  void material_rate(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, std::vector<Mat<dim>>& G);
  //! The forces - sum_p S_p grad_X w (S_p = V_p^0 P_p, or a differential) on every unknown.
  void internal_forces(const MpmState<dim>& s, const std::vector<Mat<dim>>& S, std::vector<Vec<dim>>& out);
  //! E(v) with the masses of the last unknown_mass().
  double energy(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, const std::vector<Vec<dim>>& predicted);
  //! F_p(v) into trial_F_, and the per-particle energies when `energy` (returns their sum).
  double deform(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, bool energy);
  //! Stress (weighted_stress_) and, when `derivatives`, the differentials at trial_F_.
  void linearise(const MpmState<dim>& s, bool derivatives, bool definite);
  //! (M + dt^2 K) dv with the differentials of the last linearise().
  void apply_hessian(const MpmState<dim>& s, const std::vector<Vec<dim>>& dv, std::vector<Vec<dim>>& out);
  //! With domains, each particle's two-step weight gradients q on the nodes its corners reach
  //! (domains::for_each_two_step_gradient), for the diagonal: once per solve.
  void collect_two_step_gradients(const MpmState<dim>& s);
  //! The Jacobi diagonal of M + dt^2 K, per unknown and component (Zhu et al. eq. 17, 19).
  void jacobi_diagonal(const MpmState<dim>& s, std::vector<Vec<dim>>& diagonal);
  //! Its stiffness part on the nodes of a scene without domains, added to `diagonal`.
  void jacobi_nodes(const MpmState<dim>& s, std::vector<Vec<dim>>& diagonal) const;

  std::vector<Material<dim>> materials_;
  geometry::ColliderSet<dim> colliders_;
  ImplicitSettings settings_;
  Outcome last_;
  std::int64_t unconverged_ = 0;
  std::vector<double> history_;
  std::vector<double> mass_;  // per unknown
  // Per-particle and per-corner work arrays, kept between steps to avoid reallocation.
  std::vector<Mat<dim>> grad_, trial_F_, weighted_stress_, differential_stress_, kirchhoff_;
  std::vector<Vec<dim>> corner_velocity_, corner_force_;
  struct TwoStepGradient {
    std::size_t particle;
    Index node;
    Vec<dim> q;
  };
  std::vector<TwoStepGradient> two_step_;
  std::vector<std::array<Mat<dim>, dim>> diagonal_form_;  // B_a per particle
  std::vector<Vec<dim>> merit_residual_;
  std::vector<double> energy_;
  std::vector<constitutive::StressDerivative<dim>> derivative_;
  std::vector<std::uint8_t> has_stress_;
};

}  // namespace mpm::stages
