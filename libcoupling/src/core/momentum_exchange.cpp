#include <coupling/momentum_exchange.h>
#include <coupling/shared_nodes.h>
#include <mpm/core/error.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <string>

namespace coupling {

template <int dim>
void exchange_momentum(const std::vector<double>& m_w, std::vector<mpm::Vec<dim>>& v_w, const std::vector<double>& m_s,
                       std::vector<mpm::Vec<dim>>& v_s, const std::vector<double>& K) {
  const std::size_t n = m_w.size();
  mpm::verify<mpm::InputError>(v_w.size() == n && m_s.size() == n && v_s.size() == n && K.size() == n,
                               "momentum exchange: node arrays of different sizes");
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) exchange_node<dim>(m_w[k], m_s[k], K[k], v_w[k], v_s[k]);
  });
}

template <int dim>
void MomentumExchange<dim>::apply(mpm::SparseGrid<dim>& fluid, mpm::SparseGrid<dim>& sediment,
                                  const std::vector<double>& fluid_fraction, double dt,
                                  std::vector<double>& beta) const {
  require_same_lattice(fluid, sediment, "momentum exchange");
  mpm::verify<mpm::InputError>(fluid_fraction.size() == sediment.node_storage(),
                               "momentum exchange: " + std::to_string(fluid_fraction.size()) + " fluid fractions for " +
                                   std::to_string(sediment.node_storage()) + " sediment grid nodes");
  const double volume_dt = std::pow(sediment.dx(), dim) * dt;  // V_i dt [m^3 s]
  beta.assign(sediment.node_storage(), 0.0);
  std::visit(
      [&](const auto& law) {
        for_each_shared_node(sediment, fluid, [&](std::size_t ks, std::size_t kw) {
          mpm::Vec<dim>& v_s = sediment.velocity[ks];
          mpm::Vec<dim>& v_w = fluid.velocity[kw];
          beta[ks] = law.beta(fluid_fraction[ks], (v_s - v_w).norm());
          exchange_node<dim>(fluid.mass[kw], sediment.mass[ks], beta[ks] * volume_dt, v_w, v_s);
        });
      },
      law_);
}

template void exchange_momentum<2>(const std::vector<double>&, std::vector<mpm::Vec<2>>&, const std::vector<double>&,
                                   std::vector<mpm::Vec<2>>&, const std::vector<double>&);
template void exchange_momentum<3>(const std::vector<double>&, std::vector<mpm::Vec<3>>&, const std::vector<double>&,
                                   std::vector<mpm::Vec<3>>&, const std::vector<double>&);
template class MomentumExchange<2>;
template class MomentumExchange<3>;

}  // namespace coupling
