#include <fluid/solver/weakly_compressible_solver.h>

#include <mpm/core/stages/grid_velocity_update.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace fluid {

template <int dim>
typename WeaklyCompressibleSolver<dim>::Stages WeaklyCompressibleSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::EquationOfStateForces<dim>>(eos_));
  if (colliders_.walls()) s.push_back(std::make_unique<stages::WallPressureForces<dim>>(eos_, *colliders_.walls()));
  s.push_back(std::make_unique<mpm::stages::GridVelocityUpdate<dim>>(true));
  append_viscosity<dim>(s, fluid_, colliders_);
  return s;
}

template <int dim>
typename WeaklyCompressibleSolver<dim>::Stages WeaklyCompressibleSolver<dim>::particle_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::VolumeRatioUpdate<dim>>());
  return s;
}

template <int dim>
void WeaklyCompressibleSolver<dim>::start_at_rest(mpm::Particles<dim>& particles,
                                                  const mpm::SceneSettings<dim>& settings) const {
  if (!hydrostatic_start_) return;
  const mpm::Vec<dim>& g = settings.gravity;
  int axis = 0;
  g.cwiseAbs().maxCoeff(&axis);
  if (g[axis] == 0.0 || g.norm() != std::abs(g[axis])) return;  // no gravity, or not along an axis
  const double up = g[axis] < 0.0 ? 1.0 : -1.0, dx = settings.dx;
  // The column of a particle: its dx-wide cell across the other axes; its height: up x[axis].
  const auto column = [&](const mpm::Vec<dim>& x) {
    std::array<long, dim> key{};
    for (int d = 0; d < dim; ++d) key[d] = d == axis ? 0 : static_cast<long>(std::floor(x[d] / dx));
    return key;
  };
  std::map<std::array<long, dim>, double> surface;  // height of each column's free surface [m]
  for (std::size_t p = 0; p < particles.size(); ++p) {
    // The free surface lies half a particle spacing above the highest particle.
    const double top = up * particles.x[p][axis] + 0.5 * std::pow(particles.volume0[p], 1.0 / dim);
    auto [it, inserted] = surface.try_emplace(column(particles.x[p]), top);
    if (!inserted) it->second = std::max(it->second, top);
  }
  const double bulk = eos_.density * eos_.speed_of_sound * eos_.speed_of_sound / eos_.exponent;  // B
  auto& J = particles.template channel<double>(kVolumeRatio);
  std::vector<double>* own = particles.template find_channel<double>(kLiquidVolumeRatio);  // in pores
  for (std::size_t p = 0; p < particles.size(); ++p) {
    const double depth = surface.at(column(particles.x[p])) - up * particles.x[p][axis];
    J[p] = std::pow(1.0 + eos_.density * std::abs(g[axis]) * depth / bulk, -1.0 / eos_.exponent);
    if (own) (*own)[p] = J[p];
  }
}

template class WeaklyCompressibleSolver<2>;
template class WeaklyCompressibleSolver<3>;

}  // namespace fluid
