#pragma once
//! The pressure projection of the LANS fluid on the semi-staggered grid (Gao et al.
//! 2018): after the explicit update and the boundary conditions, makes the node velocity field
//! discretely divergence-free in every fluid cell, with p = 0 in empty cells (free surface)
//! and no pressure impulse on nodes whose velocity a wall or collider prescribes. On a grid
//! with periodic axes the operator spans the whole period along them and wraps; it reads and
//! writes the canonical nodes only (the pipeline adds periodic_fill before G2P).
#include <fluid/pressure/cell_operator.h>
#include <fluid/pressure/pressure_solver.h>

#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

#include <memory>
#include <string>
#include <vector>

namespace fluid::stages {

using mpm::solve::OnFailure;

struct PressureSettings {
  std::string solver = "mgpcg";  //!< one of pressure_solver_names()
  //! Empty, or a second back-end that retries a failed solve from the same initial guess (with
  //! the same control); the retry is reported, and on_failure applies when it fails too.
  std::string fallback;
  SolveControl control;  //!< tolerance and iteration cap of every solve
  //! Solves one MGPCG hierarchy may serve within a frame (mgpcg.h; 1: a new one every solve).
  int setup_reuse = 20;
  OnFailure on_failure = OnFailure::stop;
  //! Extend the projected velocity to the loose surface nodes after the solve
  //! (surface_velocity_extension.h); off: they keep their free fall (the spurious currents).
  bool surface_extension = true;
};

//! The second phase of the mixture constraint div(n_w v_w + n_s v_s) = 0 (Gao et al. 2018),
//! one entry per grid storage node, supplied by the coupling before every projection. Without
//! it the stage is single phase: n_w = 1, n_s = 0.
template <int dim>
struct MixtureNodes {
  std::vector<double> fluid_fraction;  //!< n_w [-]
  std::vector<Vec<dim>> solid_flux;    //!< n_s v_s^* after the solid's explicit update [m/s]
  std::vector<double> solid_mobility;  //!< n_s / rho_s [m^3/kg]
};

template <int dim>
class PressureProjection final : public mpm::Stage<mpm::MpmState<dim>> {
public:
  //! `density` rho_w [kg/m^3] of the fluid; `colliders` the same obstacles as the boundary stage;
  //! `name` the stage name its messages give (the coupling's mixture projection runs one inside).
  PressureProjection(double density, mpm::geometry::ColliderSet<dim> colliders, PressureSettings settings,
                     std::string name = "pressure");

  std::string name() const override { return name_; }
  std::vector<std::string> reads() const override { return {"grid.mass", "grid.velocity", "particle.x"}; }
  std::vector<std::string> writes() const override { return {"grid.velocity", "cell.pressure"}; }
  void run(mpm::MpmState<dim>& s) override;
  //! The last pressure, the initial guess of the next solve, with its box ("box": origin and
  //! cells per axis), so that a restarted run solves from the same guess.
  mpm::CarriedData carried() const override {
    std::vector<double> box;
    for (int a = 0; a < dim; ++a) box.push_back(box_lo_[a]);
    for (int a = 0; a < dim; ++a) box.push_back(op_.cells[a]);
    return {{"pressure", p_}, {"box", box}, {"unconverged", {double(unconverged_)}}};
  }
  void restore(const mpm::CarriedData& data) override {
    for (const auto& [name, values] : data) {
      if (name == "pressure") p_ = values;
      if (name == "unconverged" && values.size() == 1) unconverged_ = static_cast<std::int64_t>(values[0]);
      if (name == "box" && values.size() == 2 * dim)
        for (int a = 0; a < dim; ++a) {
          box_lo_[a] = static_cast<int>(values[a]);
          op_.cells[a] = static_cast<int>(values[dim + a]);
        }
    }
  }

  //! A frame end, where a restart can begin: the solvers drop what they keep between solves
  //! (MGPCG's hierarchy), so that a restarted run solves as the continuous one, bit for bit.
  void synchronize(mpm::MpmState<dim>& /*state*/) override { forget(); }
  void forget() {
    solver_->forget();
    if (fallback_) fallback_->forget();
  }

  //! Couples the projection to a second phase (nullptr: single phase). The pointer must stay
  //! valid while the stage runs. The stage updates only v_w; the coupling applies
  //! v_s += dt / rho_s (D^T p) with operator() and pressure() of the same step.
  void set_mixture(const MixtureNodes<dim>* mixture) { mixture_ = mixture; }

  //! The operator of the last solve (beta_i = dt (n_w / rho_w + n_s / rho_s), 0 on prescribed
  //! and massless nodes) and the pressure per cell of its box [Pa]; cell (0, ...) of the box is
  //! the global grid cell box_origin().
  const CellOperator<dim>& cell_operator() const { return op_; }
  const std::vector<double>& pressure() const { return p_; }
  const IVec<dim>& box_origin() const { return box_lo_; }
  //! Per node of the box, phi_i: the share of the node's dual cell (the 2^dim cells around it)
  //! outside the obstacles, 1 except at slipping nodes. A slipping node on a wall holds fluid
  //! on one side only, so its mass is phi_i of a full node's and the pressure's impulse moves it
  //! 1 / phi_i as fast: its mobility in the operator is beta_i / phi_i, and the corrections of
  //! both phases there are divided by phi_i (without it, water at rest beside a slip wall
  //! feels half the hydrostatic gradient and falls along it).
  const std::vector<double>& open_share() const { return open_share_; }
  //! Pressure [Pa] of the cell holding x after the last solve (0 in empty cells and outside).
  double pressure_at(const mpm::SparseGrid<dim>& grid, const Vec<dim>& x) const;
  const SolveResult& last_result() const { return result_; }
  //! Whether the last solve stopped at the round-off floor of its system above the requested
  //! tolerance (a converged solve, but not to the tolerance asked for).
  bool stopped_at_round_off() const { return stopped_at_round_off_; }
  const PressureSettings& settings() const { return settings_; }
  //! pressure_iterations, pressure_residual (relative) and pressure_round_off (1 when the solve
  //! stopped at its round-off floor above the tolerance) of the last solve; pressure_unconverged:
  //! the solves so far (a restart included) that did not converge (pressure.on_failure: warn).
  //! An app's --check fails when it is not 0.
  std::vector<mpm::Diagnostic> diagnostics() const override {
    return {{"pressure_iterations", double(result_.iterations)},
            {"pressure_residual", result_.relative_residual},
            {"pressure_round_off", stopped_at_round_off_ ? 1.0 : 0.0},
            {"pressure_unconverged", double(unconverged_)}};
  }

private:
  //! The message of the last, failed solve by `solver`.
  std::string failure(const mpm::MpmState<dim>& s, const PressureSolver<dim>& solver) const;

  double density_;
  mpm::geometry::ColliderSet<dim> colliders_;
  PressureSettings settings_;
  std::string name_;
  std::unique_ptr<PressureSolver<dim>> solver_, fallback_;
  const MixtureNodes<dim>* mixture_ = nullptr;
  CellOperator<dim> op_;
  IVec<dim> box_lo_ = IVec<dim>::Zero();
  std::vector<double> p_;  // last pressure, the initial guess of the next solve
  std::vector<double> b_;
  std::vector<Vec<dim>> u_;
  std::vector<double> open_share_;
  SolveResult result_;
  bool stopped_at_round_off_ = false;
  std::int64_t unconverged_ = 0;  //!< solves that did not converge, over the run
  bool round_off_reported_ = false;
};

}  // namespace fluid::stages
