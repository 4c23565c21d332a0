#pragma once
//! Viscous diffusion of the node velocities by backward Euler, so that viscosity never limits
//! the time step (the explicit limit dt < dx^2 / (2 dim nu) would, for honey or mud).
#include <fluid/pressure/pressure_solver.h>

#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

#include <string>
#include <vector>

namespace fluid::stages {

template <int dim>
class ImplicitViscosity final : public mpm::Stage<mpm::MpmState<dim>> {
public:
  //! `kinematic_viscosity` nu = mu / rho [m^2/s] > 0; `colliders` give the Dirichlet velocities.
  ImplicitViscosity(double kinematic_viscosity, mpm::geometry::ColliderSet<dim> colliders, SolveControl control);

  std::string name() const override { return "viscosity"; }
  std::vector<std::string> reads() const override { return {"grid.mass", "grid.velocity"}; }
  std::vector<std::string> writes() const override { return {"grid.velocity"}; }
  void run(mpm::MpmState<dim>& s) override;

  //! Iterations and relative residual of the last CG solve.
  const SolveResult& last_result() const { return result_; }
  //! viscosity_iterations of the last solve.
  std::vector<mpm::Diagnostic> diagnostics() const override {
    return {{"viscosity_iterations", double(result_.iterations)}};
  }

private:
  double nu_;
  mpm::geometry::ColliderSet<dim> colliders_;
  SolveControl control_;
  SolveResult result_;
};

}  // namespace fluid::stages
