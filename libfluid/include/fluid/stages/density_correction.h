#pragma once
//! Particle positions relaxed towards the rest density (implicit density projection, Kugelstadt
//! et al. 2019, IEEE TVCG 25(6)): the projection makes the grid velocity divergence-free, but
//! the particles that carry the liquid drift into streaks and clumps with holes between them,
//! since nothing measures where they actually are. This stage measures it and moves them back;
//! velocities are not touched, so mass and momentum are exactly those of the step.
//!
//! After G2P, with the node masses m_i of this step's P2G:
//!   theta_c = sum over the cell's corners with beta_i > 0 of m_i / (rho dx^dim), divided by
//!             their count (the liquid's volume fraction; 1 inside a seeded lattice, less at
//!             walls and at the free surface, where the kernel reaches into empty space);
//!   r_c     = theta_c - 1 where theta_c > 1 + tolerance, else 0: only compressed cells push
//!             (cells short of particles by a wall or at the surface do not pull);
//!   D B D^T q = r on the fluid cells of the current positions (empty cells, holes included,
//!             have q = 0: the displaced particles flow into them and out through the surface),
//!             B = 1 on the nodes with mass that no wall prescribes, 0 elsewhere;
//!   u = B D^T q per node, so that D u = r: the displacement that expands each compressed
//!             cell by its excess volume;
//!   x_p += the multilinear interpolation of u in the particle's cell, at most max_shift dx.
//! The solve uses the projection's back-end (pressure.solver) at its own loose tolerance; a
//! solve that misses it moves no particle that step and is counted.
#include <fluid/pressure/cell_operator.h>
#include <fluid/pressure/pressure_solver.h>

#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

#include <memory>
#include <string>
#include <vector>

namespace fluid::stages {

struct DensityCorrectionSettings {
  double tolerance = 0.01;        //!< volume-fraction excess below which a cell is left alone
  double max_shift = 0.25;        //!< largest displacement per step [cells]
  double solve_tolerance = 1e-4;  //!< relative residual of the solve
  int max_iterations = 200;
};

template <int dim>
class DensityCorrection final : public mpm::Stage<mpm::MpmState<dim>> {
public:
  DensityCorrection(double density, mpm::geometry::ColliderSet<dim> colliders, const std::string& solver,
                    DensityCorrectionSettings settings = {});
  std::string name() const override { return "density_correction"; }
  std::vector<std::string> reads() const override { return {"grid.mass", "particle.x"}; }
  std::vector<std::string> writes() const override { return {"particle.x"}; }
  void run(mpm::MpmState<dim>& s) override;
  //! density_excess: the largest theta_c - 1 of the last step (before its correction);
  //! density_correction_unconverged: the solves so far that missed their tolerance.
  std::vector<mpm::Diagnostic> diagnostics() const override {
    return {{"density_excess", excess_}, {"density_correction_unconverged", double(unconverged_)}};
  }

private:
  double density_;
  mpm::geometry::ColliderSet<dim> colliders_;
  DensityCorrectionSettings settings_;
  std::unique_ptr<PressureSolver<dim>> solver_;
  CellOperator<dim> op_;
  std::vector<double> r_, q_;
  std::vector<mpm::Vec<dim>> u_;
  double excess_ = 0.0;
  std::int64_t unconverged_ = 0;
};

}  // namespace fluid::stages
