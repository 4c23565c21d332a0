#include <coupling/volume_fraction.h>
#include <mpm/core/error.h>
#include <mpm/core/transfer.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace coupling {

template <int dim>
void sediment_fraction(const mpm::Particles<dim>& sediment, const mpm::ParticleBuckets<dim>& buckets,
                       const mpm::Kernel& kernel, const mpm::SparseGrid<dim>& grid, double sediment_density,
                       std::vector<double>& phi) {
  mpm::verify<mpm::InputError>(sediment_density > 0.0, "sediment volume fraction: sediment density " +
                                                           std::to_string(sediment_density) + ": expected > 0");
  // phi_i = sum_p w_ip V_p / V_i: scatter V_p / V_i = m_p / (rho_s dx^dim) with the P2G weights.
  const double scale = 1.0 / (sediment_density * std::pow(grid.dx(), dim));
  std::vector<double> share(sediment.size());
  for (std::size_t p = 0; p < share.size(); ++p) share[p] = sediment.mass[p] * scale;
  mpm::scalar_to_grid(share, sediment, buckets, kernel, grid, phi);
}

VolumeFractions clamp_fractions(const std::vector<double>& phi, double min_fluid) {
  mpm::verify<mpm::InputError>(
      min_fluid > 0.0 && min_fluid <= 1.0,
      "volume fractions: minimum fluid fraction " + std::to_string(min_fluid) + ": expected a value in (0, 1]");
  VolumeFractions n;
  n.sediment.resize(phi.size());
  n.fluid.resize(phi.size());
  for (std::size_t i = 0; i < phi.size(); ++i) {
    n.sediment[i] = std::min(phi[i], 1.0 - min_fluid);
    n.fluid[i] = 1.0 - n.sediment[i];
  }
  return n;
}

template <int dim>
double cell_average(const mpm::SparseGrid<dim>& grid, const std::vector<double>& node_values,
                    const mpm::IVec<dim>& cell) {
  double sum = 0.0;
  for (int corner = 0; corner < (1 << dim); ++corner) {
    mpm::IVec<dim> node = cell;
    for (int a = 0; a < dim; ++a) node[a] += (corner >> a) & 1;
    if ((node.array() < 0).any() || (node.array() >= grid.node_counts().array()).any()) continue;
    const mpm::Index k = grid.node_index(node);
    if (k >= 0) sum += node_values[static_cast<std::size_t>(k)];
  }
  return sum / (1 << dim);
}

#define COUPLING_INSTANTIATE(dim)                                                                                   \
  template void sediment_fraction(const mpm::Particles<dim>&, const mpm::ParticleBuckets<dim>&, const mpm::Kernel&, \
                                  const mpm::SparseGrid<dim>&, double, std::vector<double>&);                       \
  template double cell_average(const mpm::SparseGrid<dim>&, const std::vector<double>&, const mpm::IVec<dim>&);
COUPLING_INSTANTIATE(2)
COUPLING_INSTANTIATE(3)

}  // namespace coupling
