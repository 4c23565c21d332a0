#include <coupling/stages/mixture_projection.h>

#include <coupling/shared_nodes.h>
#include <mpm/core/error.h>

namespace coupling::stages {

template <int dim>
MixtureProjection<dim>::MixtureProjection(double fluid_density, double sediment_density,
                                          mpm::geometry::ColliderSet<dim> colliders,
                                          fluid::stages::PressureSettings settings)
    : rho_w_(fluid_density),
      rho_s_(sediment_density),
      projection_(fluid_density, std::move(colliders), std::move(settings), "mixture_pressure") {}

template <int dim>
void MixtureProjection<dim>::run(CoupledState<dim>& s) {
  mpm::SparseGrid<dim>& gw = s.fluid.grid;
  mpm::SparseGrid<dim>& gs = s.sediment.grid;
  require_same_lattice(gw, gs, name());
  mpm::verify<mpm::Error>(s.drag.size() == gs.node_storage(),
                          "stage '" + name() + "': no drag coefficients of this step (the exchange stage runs first)");

  // Per fluid storage node: n_w, n_s v_s*, the coupled coefficients c_w, c_s and the mobility
  // that makes the projection's beta the mixture mobility B (class comment). Fluid nodes the
  // sediment grid does not hold are clear fluid: c_w = dt / rho_w, B = dt / rho_w.
  const std::size_t nw = gw.node_storage();
  const double dt = s.dt;
  mixture_.fluid_fraction.assign(nw, 1.0);
  mixture_.solid_flux.assign(nw, mpm::Vec<dim>::Zero());
  mixture_.solid_mobility.assign(nw, 0.0);
  sediment_node_.assign(nw, -1);
  c_w_.assign(nw, dt / rho_w_);
  c_s_.assign(nw, 0.0);
  for_each_shared_node(gw, gs, [&](std::size_t kw, std::size_t ks) {
    sediment_node_[kw] = static_cast<mpm::Index>(ks);
    const double n_s = s.fractions.sediment[ks], n_w = s.fractions.fluid[ks];
    if (!(gs.mass[ks] > 0.0) || !(n_s > 0.0)) return;
    const double b = s.drag[ks] * dt;
    const double a_w = n_w * rho_w_ + b, a_s = n_s * rho_s_ + b;
    const double det = a_w * a_s - b * b;
    c_w_[kw] = dt * (a_s * n_w + b * n_s) / det;
    c_s_[kw] = dt * (b * n_w + a_w * n_s) / det;
    mixture_.fluid_fraction[kw] = n_w;
    mixture_.solid_flux[kw] = n_s * gs.velocity[ks];
    mixture_.solid_mobility[kw] = (n_w * c_w_[kw] + n_s * c_s_[kw]) / dt - n_w / rho_w_;
  });
  projection_.set_mixture(&mixture_);
  projection_.run(s.fluid);

  // The rest of the corrections, with P D^T p / phi = impulse / (beta_i phi) where the operator
  // acted (beta_i = 0: a held or massless node, which the projection leaves alone; on a node
  // slipping along obstacles P projects onto the directions they leave free and phi is its open
  // share, PressureProjection::open_share(), so both phases move along the obstacles only).
  const fluid::CellOperator<dim>& op = projection_.cell_operator();
  impulse_.assign(static_cast<std::size_t>(op.node_count()), mpm::Vec<dim>::Zero());
  op.subtract_gradient(projection_.pressure(), impulse_);
  const mpm::IVec<dim> nodes = op.cells + mpm::IVec<dim>::Ones();
  mpm::IVec<dim> n = mpm::IVec<dim>::Zero();
  for (std::size_t i = 0; i < impulse_.size(); ++i) {
    const mpm::Index kw = gw.node_index(projection_.box_origin() + n);
    if (op.beta[i] > 0.0 && kw >= 0) {
      const auto k = static_cast<std::size_t>(kw);
      const mpm::Vec<dim> grad = impulse_[i] / (op.beta[i] * projection_.open_share()[i]);
      gw.velocity[k] += (c_w_[k] - dt / rho_w_) * grad;
      if (const mpm::Index ks = sediment_node_[k]; ks >= 0 && gs.mass[static_cast<std::size_t>(ks)] > 0.0)
        gs.velocity[static_cast<std::size_t>(ks)] += c_s_[k] * grad;
    }
    for (int a = 0; a < dim; ++a) {
      if (++n[a] < nodes[a]) break;
      n[a] = 0;
    }
  }
}

template class MixtureProjection<2>;
template class MixtureProjection<3>;

}  // namespace coupling::stages
