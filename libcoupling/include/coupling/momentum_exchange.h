#pragma once
//! The implicit interphase momentum exchange at the grid nodes (docs/coupling.md, the coupled step;
//! Gao et al. 2018). The drag terms of the LANS momentum equations, integrated over a node's
//! volume V_i = dx^dim and a step dt by backward Euler, with K = beta V_i dt [kg]:
//!   m_w v_w' = m_w v_w + K (v_s' - v_w'),
//!   m_s v_s' = m_s v_s + K (v_w' - v_s'),
//! per component. The exact solution: with M = m_w + m_s, the centre-of-mass velocity
//! V = (m_w v_w + m_s v_s) / M is unchanged (add the rows), and the slip r = v_s - v_w obeys
//! r' = r - K (1/m_w + 1/m_s) r' (subtract them), so
//!   r' = r m_w m_s / (m_w m_s + K M),   v_w' = V - (m_s / M) r',   v_s' = V + (m_w / M) r'.
//! Total momentum is conserved to round-off and |r'| <= |r| for every K >= 0 (0 <= K <= inf:
//! no time-step limit from drag); K -> inf gives v_w' = v_s' = V. A node with only one phase
//! is left unchanged. beta is evaluated with the slip entering the exchange (lagged
//! coefficient), which keeps the solve linear; conservation and stability hold for any beta.
//! The same beta must serve the rest of the step (the mixture projection): evaluated again at
//! the slip the exchange leaves, about a sixth of it at the fluid's step (c beta dt ~ 5), a
//! beta that grows with the slip came out too small and the grains settled 6-8 % fast.
#include <coupling/drag/drag_law.h>
#include <mpm/core/sparse_grid.h>
#include <mpm/core/types.h>

#include <vector>

namespace coupling {

//! The exchange at one node: fluid mass m_w [kg], sediment mass m_s [kg], K = beta V_i dt [kg],
//! velocities [m/s] updated in place.
template <int dim>
inline void exchange_node(double m_w, double m_s, double K, mpm::Vec<dim>& v_w, mpm::Vec<dim>& v_s) {
  if (!(m_w > 0.0) || !(m_s > 0.0)) return;
  const double M = m_w + m_s;
  const mpm::Vec<dim> V = (m_w * v_w + m_s * v_s) / M;
  const mpm::Vec<dim> r = (v_s - v_w) * (m_w * m_s / (m_w * m_s + K * M));
  v_w = V - (m_s / M) * r;
  v_s = V + (m_w / M) * r;
}

//! exchange_node for every node k of the arrays (entry k of all five is the same node).
template <int dim>
void exchange_momentum(const std::vector<double>& m_w, std::vector<mpm::Vec<dim>>& v_w, const std::vector<double>& m_s,
                       std::vector<mpm::Vec<dim>>& v_s, const std::vector<double>& K);

//! The exchange as a coupled stage calls it: on the fluid and sediment grids after
//! momentum_to_velocity (grid.velocity holds velocities), K_i = beta_i dx^dim dt with
//! beta_i = beta(n_w,i, |v_s - v_w|_i) at the slip entering the exchange.
template <int dim>
class MomentumExchange {
public:
  explicit MomentumExchange(drag::DragLaw law) : law_(law) {}

  const drag::DragLaw& law() const { return law_; }

  //! Updates grid.velocity of both grids at every node allocated in both. `fluid_fraction`
  //! n_w per storage node of `sediment` (VolumeFractions::fluid); dt [s] >= 0. `beta` gets
  //! beta_i per storage node of `sediment` (0 where the fluid grid has no node). InputError
  //! when the grids do not share their lattice or the fractions do not match the grid.
  void apply(mpm::SparseGrid<dim>& fluid, mpm::SparseGrid<dim>& sediment, const std::vector<double>& fluid_fraction,
             double dt, std::vector<double>& beta) const;

private:
  drag::DragLaw law_;
};

}  // namespace coupling
