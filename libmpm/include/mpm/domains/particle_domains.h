#pragma once
//! Particle domains (Zhu et al., "Dynamically Enriched MPM for Invertible Elasticity", sec. 4):
//! each particle owns a quadrilateral (2D) or hexahedral (3D) domain whose corners are shared
//! with its lattice neighbours, and the particles reach the grid only through the corners.
//!
//! Reference domain: the particle's seeding cell, an axis-aligned box of sides L_a centred on
//! the particle, with bilinear/trilinear corner functions N_alpha. Their averages over the box
//! (eq. 6) are constant,
//!   w_alpha_p = 1 / 2^dim,     grad_X w_alpha_p = s_alpha / (2^(dim-1) L)   (componentwise),
//! s_alpha in {-1, +1}^dim the corner's side along each axis, so that the two-step weights are
//!   w_ip = sum_alpha w_alpha_p w_i(x_alpha),   grad_X w_ip = sum_alpha w_i(x_alpha) grad_X w_alpha_p   (eq. 5)
//! with w_i the scene's grid kernel evaluated at the corner (a point). Hence
//!   P2G:  m_alpha = sum_p w_alpha_p m_p,  p_alpha = sum_p w_alpha_p m_p v_p,
//!         f_alpha = - sum_p V_p^0 P_p grad_X w_alpha_p          (eq. 8: the FEM nodal force),
//!         then m_i, (m v)_i, f_i = sum_alpha w_i(x_alpha) (m, p, f)_alpha.
//!   G2P:  v_alpha = sum_i w_i(x_alpha) v_i,  x_alpha += dt v_alpha          (eq. 9)
//!         v_p = PIC/FLIP blend of sum_alpha w_alpha_p v_alpha (and of the corner increments),
//!         x_p = sum_alpha w_alpha_p x_alpha,  F_p = sum_alpha x_alpha grad_X w_alpha_p^T  (eq. 7)
//! F_p is the mean deformation gradient of the trilinear map over the domain: it follows the
//! corners exactly, so neighbours that share corners stay connected (no numerical fracture).
//!
//! Dynamic enrichment (sec. 5): a particle whose F is badly conditioned, K(F) = sigma_min /
//! sigma_max <= epsilon (sec. 5.1), marks its corners enriched for the step. An enriched
//! corner stops at the corner layer: it keeps its m_alpha, p_alpha, f_alpha (no scatter to the
//! grid) and is integrated as a degree of freedom of its own,
//!   v_alpha = (p_alpha + dt f_alpha) / m_alpha + dt g,   x_alpha += dt v_alpha,
//! with the colliders applied at the corner, while the others go on through the grid; a
//! particle with both kinds of corners ("transitional") reaches both (eq. 11). Inside the
//! enriched region the domains are a Lagrangian FEM mesh, so the corners no longer inherit the
//! grid's interpolation error. Its explicit step is bounded by the thinnest enriched domain
//! (enriched_length) as well as by the cell.
//!
//! Material points among domains: a body seeded with domains: false (a plastic body: a
//! snowball that shatters against an elastic body with domains) gives each particle one corner
//! of its own at x_p, flagged `point`, that all its 2^dim corner slots name. Its m, p sums are
//! then the particle's own, and the corner carries the standard MPM terms the two-step weights
//! cannot give a point: the Kirchhoff stress S_p = V_p^0 tau_p, scattered as
//! f_i -= S_p grad w_i(x_p), and the gathered grad v_p = sum_i v_i grad w_i(x_p)^T that updates
//! F_p = (I + dt grad v_p) F_p. With the scene's PIC/FLIP transfer this is the standard step,
//! and a scene of material points only gives the standard pipeline's results to round-off.
//!
//! Particles of a scene with domains are never reordered (no sort moves them, no source or
//! sink adds or removes any): the corner table indexes them by storage position.
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/sparse_grid.h>
#include <mpm/core/stage.h>
#include <mpm/core/types.h>

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace mpm::domains {

template <int dim>
struct ParticleDomains {
  static constexpr int corners = 1 << dim;  //!< corners per domain

  std::vector<Vec<dim>> x;                                    //!< corner positions [m]
  std::vector<std::uint8_t> point;                            //!< per corner: 1 when a material point's own
  std::size_t point_count = 0;                                //!< particles that are material points
  std::vector<std::array<std::uint32_t, corners>> corner_of;  //!< per particle: corner alpha -> corner index
  std::vector<Vec<dim>> inverse_side;                         //!< per particle: 1 / L_a of its reference box [1/m]
  //! Corner -> (particle, alpha) pairs, packed as particle * corners + alpha: a corner's sums run
  //! in parallel over corners without two threads writing one corner.
  std::vector<std::uint32_t> sharing_begin, sharing;
  //! The bodies' surface: the domain faces no other domain shares (edges in 2D, quadrilaterals in
  //! 3D), as corner indices ordered so that the normal points out of the body as it was seeded
  //! (counter-clockwise boundary in 2D). It moves with the corners; the finer mesh of Zhu et al.
  //! sec. 4.1, where a body has one, is the embedded mesh below.
  std::vector<std::array<std::uint32_t, corners / 2>> surface;
  //! A finer surface mesh embedded in the domains (Zhu et al. sec. 4.1; embed_mesh): vertex v
  //! lies in the reference domain of particle embedded_domain[v] at the local coordinates
  //! embedded_local[v] (in [0, 1]^dim inside the domain; a vertex just outside the particles'
  //! domains follows the nearest one's trilinear map extended), and moves with the corners,
  //! x_v = sum_alpha N_alpha(xi_v) x_alpha. Triangles index the embedded vertices.
  std::vector<std::uint32_t> embedded_domain;
  std::vector<Vec<dim>> embedded_local;
  std::vector<std::array<std::uint32_t, 3>> embedded_triangles;

  //! epsilon of the enrichment criterion K(F) <= epsilon, in (0, 1); 0: never enrich.
  double enrichment_threshold = 0.0;
  //! Thickness h of the enriched surfaces' self-contact (surface_contact.h) [m]; 0: none.
  double contact_thickness = 0.0;
  // Set by mark_enrichment at the start of each step (never stored: F decides again).
  std::vector<std::uint8_t> enriched;  //!< per corner: 1 when a degree of freedom of its own this step
  std::size_t enriched_particles = 0;  //!< particles with K(F) <= epsilon
  //! The thinnest domain with an enriched corner, L_a / |F^-T e_a| over its axes [m]; infinite
  //! when none is enriched.
  double enriched_length = std::numeric_limits<double>::infinity();

  // Per-step scratch, kept to avoid allocations.
  ParticleBuckets<dim> buckets;             //!< corners ordered by grid block
  std::vector<double> mass;                 //!< m_alpha [kg]
  std::vector<Vec<dim>> momentum;           //!< p_alpha [kg m/s]; after G2P the corner velocity v_alpha [m/s]
  std::vector<Vec<dim>> force;              //!< f_alpha [N]; after G2P the FLIP increment of v_alpha [m/s]
  std::vector<Mat<dim>> velocity_gradient;  //!< grad v at a material point's corner after G2P [1/s]

  std::size_t corner_count() const { return x.size(); }
  //! True when particle p is a material point (no domain).
  bool is_point(std::size_t p) const { return point[corner_of[p][0]] != 0; }
  //! The particle whose corner c is, for a material point's corner (after index_sharing).
  std::size_t point_particle(std::size_t c) const { return sharing[sharing_begin[c]] / corners; }
  std::size_t particle_count() const { return corner_of.size(); }
  std::size_t memory_bytes() const;

  //! grad_X w_alpha_p of eq. 6 for particle p [1/m].
  Vec<dim> weight_gradient(std::size_t p, int alpha) const {
    Vec<dim> g;
    for (int a = 0; a < dim; ++a) g[a] = ((alpha >> a) & 1 ? 1.0 : -1.0) * inverse_side[p][a] / (corners / 2);
    return g;
  }
  //! sum_alpha u_alpha grad_X w_alpha_p^T: the reference gradient over particle p's domain of a
  //! field u given at the corners.
  Mat<dim> gradient(std::size_t p, const std::vector<Vec<dim>>& u) const {
    Mat<dim> G = Mat<dim>::Zero();
    for (int alpha = 0; alpha < corners; ++alpha)
      G.noalias() += u[corner_of[p][alpha]] * weight_gradient(p, alpha).transpose();
    return G;
  }
  //! F_p = sum_alpha x_alpha grad_X w_alpha_p^T from the current corners.
  Mat<dim> deformation(std::size_t p) const { return gradient(p, x); }
  //! The current position of embedded vertex v, sum_alpha N_alpha(xi_v) x_alpha [m].
  Vec<dim> embedded_position(std::size_t v) const {
    Vec<dim> x_v = Vec<dim>::Zero();
    for (int alpha = 0; alpha < corners; ++alpha) {
      double N = 1.0;
      for (int a = 0; a < dim; ++a) N *= (alpha >> a) & 1 ? embedded_local[v][a] : 1.0 - embedded_local[v][a];
      x_v += N * x[corner_of[embedded_domain[v]][alpha]];
    }
    return x_v;
  }
  //! x_p = sum_alpha w_alpha_p x_alpha.
  Vec<dim> centre(std::size_t p) const {
    Vec<dim> c = Vec<dim>::Zero();
    for (int alpha = 0; alpha < corners; ++alpha) c += x[corner_of[p][alpha]];
    return c / corners;
  }
};

//! Gives the particles [first, first + positions.size()) domains: `positions` lie on an
//! axis-aligned lattice of spacing `spacing` [m] (geometry/seeding.h) and start deformed by the
//! diagonal `stretch` (a body's F = diag(stretch) at seeding), so each reference box has sides
//! spacing / |stretch_a| and the corners sit at the deformed lattice's cell corners. Corners
//! are shared within this call only: separate bodies do not stick together. Error when a
//! position is off the lattice by more than 1e-6 spacings or `first` is not the particle count
//! so far.
template <int dim>
void add_body(ParticleDomains<dim>& domains, std::size_t first, const std::vector<Vec<dim>>& positions, double spacing,
              const Vec<dim>& stretch);

//! Embeds a triangle mesh (Zhu et al. sec. 4.1) in the domains of the body that add_body seeded
//! from the same `positions` and `spacing` as particles [first, first + positions.size()): the
//! mesh's `vertices` [m], in the frame of the seeded positions (the mesh the body was seeded
//! from), each in the domain whose lattice cell holds it or, outside the particles' cells, in
//! the domain of the nearest particle within two spacings; `triangles` index `vertices`. The
//! embedded mesh then moves with the corners (embedded_position). Error naming the first
//! vertex with no particle within two spacings, or a triangle index out of range.
template <int dim>
void embed_mesh(ParticleDomains<dim>& domains, std::size_t first, const std::vector<Vec<dim>>& positions,
                double spacing, const std::vector<Vec<dim>>& vertices,
                const std::vector<std::array<std::uint32_t, 3>>& triangles);

//! Gives the particles [first, first + positions.size()) no domain: each is a material point,
//! a corner of its own at its position (see above). Error when `first` is not the particle
//! count so far.
template <int dim>
void add_points(ParticleDomains<dim>& domains, std::size_t first, const std::vector<Vec<dim>>& positions);

//! The corner -> particle table (sharing_begin, sharing) and the surface, after the last add_body.
template <int dim>
void index_sharing(ParticleDomains<dim>& domains);

//! K(F) = 1 / (|F^-1|_2 |F|_2) = sigma_min / sigma_max in [0, 1], the reciprocal of F's condition
//! number (Zhu et al. sec. 5.1; their eq. 10 prints Frobenius norms, which would give a
//! rotation 1/dim): 1 for a rotation times a uniform scaling, 0 for a flat domain.
template <int dim>
double enrichment_metric(const Mat<dim>& F);

//! Marks the corners of every particle with a domain and K(F_p) <= domains.enrichment_threshold and sets
//! enriched_particles; clears the marks when the threshold is 0. With `explicit_step` (the
//! enriched corners are stepped explicitly) also enriched_length, and a NumericalError naming
//! the first enriched domain thinner than 1e-6 of its rest size (no explicit step is stable
//! through it); an implicit step needs neither.
template <int dim>
void mark_enrichment(ParticleDomains<dim>& domains, const std::vector<Mat<dim>>& F, bool explicit_step = true);

//! Sorts the corners into buckets of `grid` (allocating the blocks their stencils touch) and
//! scatters m_alpha, p_alpha, f_alpha (in domains.mass, momentum, force) of the corners not
//! enriched into grid.mass, grid.velocity (momentum) and grid.force, each zeroed first, and
//! the material points' stress S_p = V_p^0 tau_p (`point_stress`, indexed by particle; read
//! only at points) as - S_p grad w_i. NumericalError naming `stage` when a corner (enriched or
//! not) is not finite or its stencil leaves the grid.
template <int dim>
void corners_to_grid(ParticleDomains<dim>& domains, const Kernel& kernel, SparseGrid<dim>& grid,
                     const std::string& stage, const std::vector<Mat<dim>>& point_stress = {});

//! For the corners not enriched: v_alpha = sum_i w_i(x_alpha) v_i into domains.momentum, with
//! `flip` the increment sum_i w_i (v_i - v_i^old) into domains.force, and at the material
//! points' corners grad v into domains.velocity_gradient. Enriched corners keep their p_alpha
//! and f_alpha for integrate_enriched.
template <int dim>
void grid_to_corners(ParticleDomains<dim>& domains, const Kernel& kernel, const SparseGrid<dim>& grid, bool flip);

//! The enriched corners' own update: v_alpha = (p_alpha + dt f_alpha) / m_alpha + dt g, then
//! `constrain(x_alpha, v_alpha)` (the colliders), into domains.momentum and the increment
//! v_alpha - p_alpha / m_alpha into domains.force.
template <int dim>
void integrate_enriched(ParticleDomains<dim>& domains, double dt, const Vec<dim>& gravity,
                        const std::function<void(const Vec<dim>&, Vec<dim>&)>& constrain);

//! f_alpha = - sum_p S_p grad_X w_alpha_p on every corner (eq. 8), S_p = V_p^0 P_p the
//! particle's first Piola-Kirchhoff stress weighted by its reference volume [N m].
template <int dim>
void corner_forces(const ParticleDomains<dim>& domains, const std::vector<Mat<dim>>& weighted_stress,
                   std::vector<Vec<dim>>& out);

//! out_alpha = sum_i w_i(x_alpha) u_i for the corners not enriched, any node field u (sized at
//! least to the node storage; the grid_to_corners interpolation); enriched entries untouched.
//! Preconditions: the corners sorted against `grid` (corners_to_grid).
template <int dim>
void corners_from_nodes(const ParticleDomains<dim>& domains, const Kernel& kernel, const SparseGrid<dim>& grid,
                        const std::vector<Vec<dim>>& u, std::vector<Vec<dim>>& out);

//! out_i = sum_alpha w_i(x_alpha) f_alpha over the corners not enriched (out sized to the node
//! storage, zeroed first): the transpose of corners_from_nodes.
template <int dim>
void nodes_from_corners(const ParticleDomains<dim>& domains, const Kernel& kernel, const SparseGrid<dim>& grid,
                        const std::vector<Vec<dim>>& f, std::vector<Vec<dim>>& out);

//! body(p, node, q) for every particle p and every grid node its corners not enriched reach, with
//! q = sum_alpha w_node(x_alpha) grad_X w_alpha_p the reference gradient of the two-step weight
//! (eq. 5) [1/m]; serially, in particle order. For the diagonal of an implicit step's operator.
template <int dim>
void for_each_two_step_gradient(const ParticleDomains<dim>& domains, const Kernel& kernel, const SparseGrid<dim>& grid,
                                const std::function<void(std::size_t, Index, const Vec<dim>&)>& body);

//! x_alpha += dt v_alpha for every corner (v_alpha in domains.momentum).
template <int dim>
void advance_corners(ParticleDomains<dim>& domains, double dt);

//! The corner positions, for a checkpoint ("domains/x"), and their restoration into domains
//! seeded the same way: IoError-free check, Error when the sizes differ.
template <int dim>
CarriedData carried(const ParticleDomains<dim>& domains);
template <int dim>
void restore(ParticleDomains<dim>& domains, const CarriedData& data);

}  // namespace mpm::domains
