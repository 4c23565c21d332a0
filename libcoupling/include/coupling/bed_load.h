#pragma once
//! A sub-grid bed-load layer at the surface of a sediment bed (docs/coupling.md, "Bed load at
//! the bed surface").
//!
//! A grid of dx >> d cannot resolve the few grain diameters in which a current moves a bed: the
//! drag of the first cell's water, at nearly the free-stream speed, would move the sand of the
//! whole cell (the flat-bed flume measured 39-162 times the Meyer-Peter & Mueller flux without
//! this closure). At the bed surface the closure puts back what a resolved boundary layer gives:
//! - the wall stress of a rough-wall log law, tau_b = rho_w u_*^2, with u_* from the column's
//!   depth-averaged water speed U relative to the bed's grains and its depth h by Keulegan's
//!   U / u_* = ln(11 h / k_s) / kappa (kappa = 0.4, k_s = roughness * d, Nikuradse): the
//!   column's water is the run of nodes with water above the bed surface, up to the first node
//!   without water (the free surface) or inside an obstacle (below a pipe: the gap). The depth
//!   average is set by the discharge,
//!   not by the shape of a boundary layer the grid does not resolve (the water's speed one or two
//!   nodes above the bed came out about half the log law's in the flume). The tangential drag
//!   impulse of the bed-surface layer (the surface node and the node above it, per column) is
//!   limited to tau_b dx^(dim-1) dt, each node's exchange scaled alike so that momentum stays
//!   conserved (a wall function for the water, Launder & Spalding 1974); the normal drag
//!   (seepage, settling) is unchanged;
//! - the bed load of a transport formula, q_b = a (theta - theta_c)^b sqrt((s - 1) g d^3) with
//!   theta = tau_b / ((rho_s - rho_w) g d) (Meyer-Peter & Mueller 1948: a = 8, b = 1.5,
//!   theta_c = 0.047), along the stress, carried by the layer's grains as a drift of their
//!   positions (grains rolling over the bed: their strain and momentum are not changed, the
//!   mass balance is Exner's). A column's drift velocity u_d makes the layer's mass flux the
//!   formula's: sum_layer m_i u_d = rho_s q_b dx^(dim-1), so sum_p m_p u_d(x_p) over the
//!   column's particles is the same (the gather is the adjoint of the P2G that gave m_i). u_d
//!   is capped at the water's speed u. A morphological factor multiplies q_b so that the bed
//!   evolves that many times faster than the flow (Roelvink 2006): a scour's time scale is then
//!   the run's time times the factor.
//! - optionally, the grains' pick-up and deposition over a step length L (Einstein 1950; Nakagawa &
//!   Tsujimoto 1980; Phillips & Sutherland 1989): grains are picked up at the rate q_e / L and
//!   land at q / L, so the flux q relaxes toward the formula's q_e along the transport,
//!   (e . grad) q = (q_e - q) / L. With L = 0 (the default) q = q_e in every column (local
//!   equilibrium): the bed answers a change of the current within a cell, so a scour hole's edges
//!   are as sharp as the grid. L is a length [m] or van Rijn's (1984a) saltation length
//!   lambda_b = 3 d D*^0.6 T^0.9 of the column's Shields number.
//! Not modelled: the slope's effect on the threshold (avalanching on slopes is the continuum's
//! plasticity), suspended load lifted above the bed-surface layer, hiding in mixtures.
#include <coupling/volume_fraction.h>
#include <mpm/core/sparse_grid.h>
#include <mpm/core/types.h>
#include <mpm/geometry/collider.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace coupling {

//! von Karman's constant of the log law [-] (1 / 2.5, as Keulegan's depth-averaged law is quoted).
inline constexpr double von_karman = 0.4;

//! The transport formula and the wall law with the grains' and the water's constants.
struct BedLoadLaw {
  double grain_diameter = 5e-4;       //!< d [m] > 0
  double fluid_density = 1000.0;      //!< rho_w [kg/m^3] > 0
  double sediment_density = 2650.0;   //!< rho_s [kg/m^3] > rho_w
  double gravity = 9.81;              //!< |g| [m/s^2] > 0
  double critical_shields = 0.047;    //!< theta_c >= 0
  double coefficient = 8.0;           //!< a > 0
  double exponent = 1.5;              //!< b > 0
  double roughness = 2.5;             //!< k_s / d > 0
  double morphological_factor = 1.0;  //!< >= 1: the bed's time over the flow's
  double surface_fraction = 0.3;      //!< n_s that marks the bed surface, in (0, 1)
  double fluid_viscosity = 1.0e-3;    //!< mu [Pa s] > 0 (van Rijn's D*)
  double step_length = 0.0;           //!< L [m] >= 0 of the pick-up and deposition (0: q = q_e)
  bool van_rijn_step = false;         //!< L = saltation_length(theta) of each column instead

  //! u_* [m/s] of water of depth-averaged `speed` [m/s] >= 0 and `depth` h [m] over a rough
  //! bed: U / u_* = ln(11 h / k_s) / kappa; requires in_log_layer(h).
  double friction_velocity(double speed, double depth) const;
  //! Whether h is deep enough for the law: 11 h / k_s > e.
  bool in_log_layer(double depth) const;
  //! The wall stress [Pa] at which grains settling at `settling_velocity` w_s [m/s] have the
  //! Rouse number P = w_s / (kappa u_*) = `rouse_number`: rho_w (w_s / (kappa P))^2.
  double suspending_stress(double settling_velocity, double rouse_number) const;
  //! theta of a friction velocity [m/s].
  double shields_number(double friction_velocity) const;
  //! q_b [m^2/s] of grain volume per unit width at Shields number theta (0 below theta_c),
  //! without the morphological factor.
  double flux(double shields) const;
  //! van Rijn's (1984a) saltation length lambda_b = 3 d D*^0.6 T^0.9 [m], with the particle
  //! parameter D* = d ((s - 1) g / nu^2)^(1/3) and the transport stage T = (theta - theta_c) /
  //! theta_c; 0 at or below the threshold.
  double saltation_length(double shields) const;
  //! The step length L [m] of a column at Shields number theta (step_length or lambda_b).
  double step_length_at(double shields) const { return van_rijn_step ? saltation_length(shields) : step_length; }
  //! Whether the flux relaxes over a step length (else q = q_e in each column).
  bool picks_up() const { return van_rijn_step || step_length > 0.0; }
};

//! The bed-load flux of each column where the grains' pick-up (q_e / L) and deposition (q / L)
//! balance their transport: (e . grad) q = (q_e - q) / L, e the column's unit direction of
//! transport, discretised upwind on the columns' lattice (the node lattice `counts` without the
//! axis `up`, spacing dx [m]): q_i (1 + L_i sum_a |e_a| / dx) = q_e,i + (L_i / dx) sum_a |e_a| q_(i - sign(e_a) 1_a).
//! A column with e = 0 (no bed or no current) carries nothing and passes nothing on; nothing
//! enters from outside the lattice. L_i = 0 gives q_i = q_e,i. Solved by Gauss-Seidel sweeps in
//! the 2^(dim-1) orders of the horizontal axes (one sweep is exact where every column's e points
//! the same way); returns the sweeps it took (at most `max_sweeps`, after which the last iterate
//! stands). `capacity`, `direction`, `length` and `flux` have one entry per column.
template <int dim>
int relax_to_capacity(const mpm::IVec<dim>& counts, int up, double dx, const std::vector<mpm::Vec<dim>>& capacity,
                      const std::vector<mpm::Vec<dim>>& direction, const std::vector<double>& length,
                      std::vector<mpm::Vec<dim>>& flux, int max_sweeps = 256);

//! One node of a bed-surface layer: its storage index on each phase grid (fluid -1 where the
//! fluid grid holds no water there), its column, and the velocities the exchange starts from.
template <int dim>
struct BedLayerNode {
  std::size_t sediment = 0;
  std::int64_t fluid = -1;
  std::int64_t column = 0;
  mpm::Vec<dim> v_s = mpm::Vec<dim>::Zero(), v_w = mpm::Vec<dim>::Zero();
};

//! The bed-surface layer of a step: per column (the lattice's node columns along the vertical),
//! the wall stress [Pa] on the bed and the layer's drift velocity [m/s] (zero where the column
//! has no bed or no water above it).
template <int dim>
struct BedLayer {
  int up = 1;  //!< the vertical axis (gravity along -up)
  std::vector<BedLayerNode<dim>> nodes;
  std::vector<mpm::Vec<dim>> stress, drift;
  std::vector<mpm::Vec<dim>> flux;            //!< q [m^2/s] of grain volume, times the morphological factor
  std::vector<mpm::Vec<dim>> particle_drift;  //!< u_d gathered to each sediment particle [m/s]
  double largest_shields = 0.0;               //!< over the columns [-]
};

//! The column of the node nearest x [m] (the node lattice's columns along the vertical axis
//! `up`, numbered as find_bed_layer numbers them: the horizontal node coordinates, the first
//! axis the fastest); -1 where that node lies outside the lattice.
template <int dim>
std::int64_t bed_column(const mpm::SparseGrid<dim>& grid, int up, const mpm::Vec<dim>& x);

//! Finds the layer (per column the highest sediment node with n_s >= surface_fraction and the
//! node above it), the wall stress from the column's depth-averaged water above it and the
//! drift, and records the nodes' velocities before the exchange. `up`: the vertical axis.
//! Nodes that the obstacles prescribe at `time` (ColliderSet::prescribes: in a wall's layer,
//! inside a sill or a pipe; boundary nodes, whose velocities the walls and colliders set) are
//! neither surface nodes nor the column's water, so a column in a wall's layer has no layer. A
//! column without water above its surface node (below a pipe resting on the bed), without
//! current or shallower than the log layer gets no stress, and limit_bed_shear then takes all
//! the tangential drag out of its layer: no current, no wall stress.
template <int dim>
void find_bed_layer(const BedLoadLaw& law, int up, const mpm::SparseGrid<dim>& fluid,
                    const mpm::SparseGrid<dim>& sediment, const VolumeFractions& fractions,
                    const mpm::geometry::ColliderSet<dim>& obstacles, double time, BedLayer<dim>& layer);

//! After the exchange: scales each column's exchange at its layer nodes, tangential components
//! only, so that the layer's tangential impulse is at most |stress| dx^(dim-1) dt (momentum
//! of each node unchanged by the scaling). Returns the number of columns limited.
template <int dim>
std::size_t limit_bed_shear(const BedLayer<dim>& layer, mpm::SparseGrid<dim>& fluid, mpm::SparseGrid<dim>& sediment,
                            double dt);

}  // namespace coupling
