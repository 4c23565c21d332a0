// Density correction (density_correction.h): theta per cell from this step's node masses, the
// operator of the projection with B = 1, then the displacement interpolated to each particle.
#include <fluid/stages/density_correction.h>
#include <fluid/stages/prescribed_nodes.h>

#include "fluid_cell.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace fluid::stages {

template <int dim>
DensityCorrection<dim>::DensityCorrection(double density, mpm::geometry::ColliderSet<dim> colliders,
                                          const std::string& solver, DensityCorrectionSettings settings)
    : density_(density),
      colliders_(std::move(colliders)),
      settings_(settings),
      solver_(make_pressure_solver<dim>(solver)) {}

template <int dim>
void DensityCorrection<dim>::run(mpm::MpmState<dim>& s) {
  mpm::SparseGrid<dim>& g = s.grid;
  auto& X = s.particles.x;
  excess_ = 0.0;
  if (X.empty()) return;

  // The operator box of the current positions; B = 1 where the grid has mass and no wall.
  const mpm::IVec<dim> lo = fluid_cell_box(g, X, op_);
  const std::vector<std::uint8_t> fixed = prescribed_nodes(g, colliders_, s.time + s.dt);
  const std::int64_t nodes = op_.node_count();
  op_.beta.assign(static_cast<std::size_t>(nodes), 0.0);
  std::vector<double> fill(static_cast<std::size_t>(nodes), 0.0);  // m_i / (rho dx^dim)
  const double full = density_ * std::pow(g.dx(), dim);
  for_each_point<dim>(op_.node_extent(), [&](const mpm::IVec<dim>& n, std::int64_t i) {
    const mpm::Index k = g.node_index(lo + n);
    if (k < 0 || !(g.mass[k] > 0.0) || fixed[k]) return;
    op_.beta[i] = 1.0;
    fill[i] = g.mass[k] / full;
  });
  drop_cells_without_unknowns(op_);

  // r_c: the excess volume fraction of the compressed cells.
  r_.assign(static_cast<std::size_t>(op_.cell_count()), 0.0);
  bool any = false;
  for_each_point<dim>(op_.cells, [&](const mpm::IVec<dim>& c, std::int64_t ci) {
    if (op_.type[ci] != CellType::fluid) return;
    double sum = 0.0;
    int count = 0;
    for (int corner = 0; corner < (1 << dim); ++corner) {
      mpm::IVec<dim> n = c;
      for (int a = 0; a < dim; ++a) n[a] += (corner >> a) & 1;
      const std::int64_t i = op_.node_index(n);
      if (op_.beta[i] > 0.0) {
        sum += fill[i];
        ++count;
      }
    }
    const double theta = count > 0 ? sum / count : 0.0;
    excess_ = std::max(excess_, theta - 1.0);
    if (theta > 1.0 + settings_.tolerance) {
      r_[ci] = theta - 1.0;
      any = true;
    }
  });
  if (!any) return;

  SolveControl control;
  control.relative_tolerance = settings_.solve_tolerance;
  control.max_iterations = settings_.max_iterations;
  q_.clear();
  const SolveResult result = solver_->solve(op_, r_, q_, control);
  if (!result.converged) {
    ++unconverged_;
    return;
  }
  u_.assign(static_cast<std::size_t>(nodes), mpm::Vec<dim>::Zero());
  op_.subtract_gradient(q_, u_);

  // x_p += u at x_p (multilinear in its cell), at most max_shift dx long.
  const double dx = g.dx(), cap = settings_.max_shift * dx;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, X.size(), 1024), [&](const auto& range) {
    for (std::size_t p = range.begin(); p != range.end(); ++p) {
      const mpm::IVec<dim> cell = fluid_cell_of(g, X[p]);
      mpm::Vec<dim> xi;
      for (int a = 0; a < dim; ++a) {
        // On a periodic axis the particle may sit in a ghost image of its canonical cell.
        const double local = (X[p][a] - g.origin()[a]) / dx;
        xi[a] = std::clamp(local - std::floor(local), 0.0, 1.0);
      }
      mpm::Vec<dim> shift = mpm::Vec<dim>::Zero();
      for (int corner = 0; corner < (1 << dim); ++corner) {
        mpm::IVec<dim> n = cell - lo;
        double w = 1.0;
        for (int a = 0; a < dim; ++a) {
          const int bit = (corner >> a) & 1;
          n[a] += bit;
          w *= bit ? xi[a] : 1.0 - xi[a];
        }
        shift += w * u_[static_cast<std::size_t>(op_.node_index(n))];
      }
      const double length = shift.norm();
      X[p] += length > cap ? (cap / length) * shift : shift;
    }
  });
}

template class DensityCorrection<2>;
template class DensityCorrection<3>;

}  // namespace fluid::stages
