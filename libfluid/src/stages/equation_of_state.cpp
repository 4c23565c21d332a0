// The weakly compressible liquid (equation_of_state.h):
//   p_p = max(0, B (J_p^-gamma - 1)),  B = rho_0 c^2 / gamma        (Tait; Becker & Teschner 2007 eq. 7)
//   f_i = - sum_p V_p^0 tau_p grad w_ip,  tau_p = -p_p J_p I           (Kirchhoff stress of a pressure)
//   J_p <- det(I + dt grad v_p) J_p                                     (after the final grid velocity)
#include <fluid/stages/equation_of_state.h>

#include <mpm/core/error.h>
#include <mpm/core/finite_guard.h>
#include <mpm/core/transfer.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace fluid {

double TaitEquationOfState::pressure(double J) const {
  const double B = density * speed_of_sound * speed_of_sound / exponent;
  return std::max(0.0, B * (std::pow(J, -exponent) - 1.0));
}

namespace stages {

template <int dim>
void EquationOfStateForces<dim>::run(mpm::MpmState<dim>& s) {
  const mpm::Particles<dim>& P = s.particles;
  const std::vector<double>& J = P.template channel<double>(kVolumeRatio);
  weighted_stress_.resize(P.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p)
      weighted_stress_[p] = (-P.volume0[p] * eos_.pressure(J[p]) * J[p]) * mpm::Mat<dim>::Identity();
  });
  mpm::stress_to_grid_forces(weighted_stress_, P, s.buckets, s.kernel, s.grid);
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
  for (std::size_t p = 0; p < J.size(); ++p) {
    if (!(J[p] > 0.0))
      throw mpm::NumericalError("stage '" + name() + "': particle " + std::to_string(p) +
                                " was compressed to J = " + std::to_string(J[p]) + " at t = " + std::to_string(s.time) +
                                " s: the step exceeds the acoustic limit (lower time.wave_cfl)");
    if (J[p] < 1.0) deviation_ = std::max(deviation_, 1.0 / J[p] - 1.0);
  }
}

template class EquationOfStateForces<2>;
template class EquationOfStateForces<3>;
template class VolumeRatioUpdate<2>;
template class VolumeRatioUpdate<3>;

}  // namespace stages
}  // namespace fluid
