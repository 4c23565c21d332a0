// The weakly compressible liquid (equation_of_state.h):
//   p_p = max(0, B (J_p^-gamma - 1)),  B = rho_0 c^2 / gamma        (Tait; Becker & Teschner 2007 eq. 7)
//   f_i = - sum_p V_p^0 tau_p grad w_ip,  tau_p = -p_p J_p I           (Kirchhoff stress of a pressure)
//   J_p <- det(I + dt grad v_p) J_p                                     (after the final grid velocity)
//   wall images: f_ia += V_p J_p p_w d_a w_i(x'), p_w = max(0, p_p + rho_p g . (x_w - x_p))  (Adami et al. 2012 eq. 27)
//   p_p of the particle's own volume ratio (own_volume_ratio: J, or the pore liquid's V_own / V^0)
#include <fluid/stages/equation_of_state.h>

#include <mpm/core/error.h>
#include <mpm/core/finite_guard.h>
#include <mpm/core/transfer.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>
#include <variant>

namespace fluid {

double TaitEquationOfState::pressure(double J) const {
  const double B = density * speed_of_sound * speed_of_sound / exponent;
  return std::max(0.0, B * (std::pow(J, -exponent) - 1.0));
}

namespace stages {

namespace {

//! A closed wall's plane (the inner face of its layer) along one axis.
struct WallPlane {
  double position;  //!< [m]
  double inward;    //!< +1 for a lower wall (the liquid lies above), -1 for an upper one
};

//! Steps offset through the S^dim nodes of a stencil, first axis fastest; false after the last.
template <int dim, int S>
bool next_stencil_node(std::array<int, dim>& offset) {
  for (int a = 0; a < dim; ++a) {
    if (++offset[a] < S) return true;
    offset[a] = 0;
  }
  return false;
}

}  // namespace

template <int dim>
void EquationOfStateForces<dim>::run(mpm::MpmState<dim>& s) {
  const mpm::Particles<dim>& P = s.particles;
  const std::vector<double>& J = P.template channel<double>(kVolumeRatio);
  const std::vector<double>& own = own_volume_ratio(P);
  weighted_stress_.resize(P.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p)
      weighted_stress_[p] = (-P.volume0[p] * eos_.pressure(own[p]) * J[p]) * mpm::Mat<dim>::Identity();
  });
  mpm::stress_to_grid_forces(weighted_stress_, P, s.buckets, s.kernel, s.grid);
}

template <int dim>
void WallPressureForces<dim>::run(mpm::MpmState<dim>& s) {
  const mpm::Particles<dim>& P = s.particles;
  const std::vector<double>& J = P.template channel<double>(kVolumeRatio);
  const std::vector<double>& own = own_volume_ratio(P);
  mpm::SparseGrid<dim>& grid = s.grid;
  const double dx = grid.dx();
  const double reach = 0.5 * mpm::kernel_support(s.kernel) * dx;  // a stencil's nodes lie within this
  const double tolerance = 1e-9 * dx;  // a node on a plane belongs to the wall (DomainWalls::project)

  // Up to two planes per axis (a domain thinner than two reaches has both within reach).
  std::vector<std::pair<int, WallPlane>> planes;
  for (int a = 0; a < dim; ++a) {
    if (walls_.wall(a, mpm::geometry::Side::lower)) planes.push_back({a, {walls_.lo()[a] + walls_.thickness(), 1.0}});
    if (walls_.wall(a, mpm::geometry::Side::upper)) planes.push_back({a, {walls_.hi()[a] - walls_.thickness(), -1.0}});
  }

  // Fixed chunks of particles, each listing its pushes in particle order, then added chunk by
  // chunk: the same sums in the same order for any thread count.
  constexpr std::size_t chunk = 4096;
  pushes_.resize((P.size() + chunk - 1) / chunk);
  std::visit(
      [&](const auto& kernel) {
        constexpr int S = std::decay_t<decltype(kernel)>::support;
        tbb::parallel_for(std::size_t{0}, pushes_.size(), [&](std::size_t c) {
          std::vector<Push>& out = pushes_[c];
          out.clear();
          for (std::size_t p = c * chunk; p < std::min(P.size(), (c + 1) * chunk); ++p)
            for (const auto& [a, plane] : planes) {
              const mpm::Vec<dim>& x = P.x[p];
              const double depth = plane.inward * (x[a] - plane.position);
              if (!(depth > 0.0 && depth < reach)) continue;
              mpm::Vec<dim> image = x;
              image[a] = 2.0 * plane.position - x[a];
              // f_ia += V_p J_p p_wall d_a w_i(x') on the nodes strictly on the liquid's side: along
              // a, the nodes past the plane whose weight still changes at the image (none when the
              // particle lies deeper than the support beyond the first such node).
              int base[dim];
              double w[dim][S], dw[dim][S];
              bool past[S], reaches = false;
              kernel((image[a] - grid.origin()[a]) / dx, base[a], w[a], dw[a]);
              for (int n = 0; n < S; ++n) {
                past[n] = plane.inward * (grid.origin()[a] + (base[a] + n) * dx - plane.position) > tolerance;
                reaches = reaches || (past[n] && dw[a][n] != 0.0);
              }
              if (!reaches) continue;
              // The pressure at the wall point below the particle, held over its image.
              mpm::Vec<dim> wall_point = x;
              wall_point[a] = plane.position;
              const double wall_pressure =
                  std::max(0.0, eos_.pressure(own[p]) + eos_.density / own[p] * s.gravity.dot(wall_point - x));
              if (wall_pressure == 0.0) continue;
              for (int b = 0; b < dim; ++b)
                if (b != a) kernel((image[b] - grid.origin()[b]) / dx, base[b], w[b], dw[b]);
              const double scale = P.volume0[p] * J[p] * wall_pressure / dx;
              std::array<int, dim> offset{};
              do {
                if (!past[offset[a]]) continue;
                mpm::IVec<dim> node;
                double force = scale;
                for (int b = 0; b < dim; ++b) {
                  node[b] = base[b] + offset[b];
                  force *= b == a ? dw[b][offset[b]] : w[b][offset[b]];
                }
                const mpm::Index i = force != 0.0 ? grid.node_index(node) : -1;
                if (i >= 0) out.push_back({i, a, force});
              } while (next_stencil_node<dim, S>(offset));
            }
        });
      },
      s.kernel);
  for (const std::vector<Push>& out : pushes_)
    for (const Push& push : out) grid.force[push.node][push.axis] += push.force;
}

template <int dim>
void VolumeRatioUpdate<dim>::run(mpm::MpmState<dim>& s) {
  mpm::Particles<dim>& P = s.particles;
  std::vector<double>& J = P.template channel<double>(kVolumeRatio);
  mpm::velocity_gradient(P, s.buckets, s.kernel, s.grid, grad_v_);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p)
      J[p] *= (mpm::Mat<dim>::Identity() + s.dt * grad_v_[p]).determinant();
  });
  mpm::check_finite(J, name(), "particle", "volume ratio J");
  deviation_ = 0.0;
  const std::vector<double>& own = own_volume_ratio(P);
  for (std::size_t p = 0; p < J.size(); ++p) {
    if (!(J[p] > 0.0))
      throw mpm::NumericalError("stage '" + name() + "': particle " + std::to_string(p) +
                                " was compressed to J = " + std::to_string(J[p]) + " at t = " + std::to_string(s.time) +
                                " s: the step exceeds the acoustic limit (lower time.wave_cfl)");
    if (own[p] < 1.0) deviation_ = std::max(deviation_, 1.0 / own[p] - 1.0);
  }
}

template class EquationOfStateForces<2>;
template class EquationOfStateForces<3>;
template class WallPressureForces<2>;
template class WallPressureForces<3>;
template class VolumeRatioUpdate<2>;
template class VolumeRatioUpdate<3>;

}  // namespace stages
}  // namespace fluid
