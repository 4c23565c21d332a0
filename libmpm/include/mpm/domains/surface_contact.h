#pragma once
//! Self-contact of enriched particle domains. Enriched corners skip the grid
//! (particle_domains.h), and the grid is what keeps MPM material from passing through itself:
//! without contact of their own, an enriched part pushed into the body folds through it and the
//! tangled elements lock the deformation in. Here the bodies' surface (ParticleDomains::surface)
//! meets the vertices that can run into it: the surface's own corners and the material points.
//!
//! Once per step, with the corner velocities known and before the corners move: every pair of
//! a vertex c and a surface face f (an edge in 2D; in 3D a quadrilateral, as the two triangles
//! (0, 1, 2) and (0, 2, 3)) that has an enriched corner among its corners and c's, and that
//! shares no domain with c, is a contact when its gap would close below the thickness h in the
//! step. With x_f = sum_k b_k x_k the point of f closest to x_c (barycentric b_k), the gap
//! g = |x_c - x_f|, the normal n = (x_c - x_f) / g and the normal velocity
//! v_n = (v_c - sum_k b_k v_k) . n, the condition is g + dt v_n < min(g, h), and the pair gets the
//! inelastic normal impulse J n that makes it an equality (Bridson, Fedkiw & Anderson 2002,
//! "Robust treatment of collisions, contact and friction for cloth animation", sec. 7.1):
//!   J = m_eff (min(0, (h - g) / dt) - v_n),   1 / m_eff = 1 / m_c + sum_k b_k^2 / m_k,
//!   v_c += J n / m_c,   v_k -= b_k J n / m_k.
//! A pair never closes below min(g, h); a gap wider than h may close to h in one step. The
//! impulses conserve linear momentum exactly and angular momentum too (each acts along the
//! line through x_c and x_f); there is no tangential impulse (frictionless), and a separating
//! pair is left alone. The pairs are swept in a fixed order (Gauss-Seidel) until none needs an
//! impulse or `sweeps` are done, serially: the result does not depend on the thread count.
//! Not covered: edge-edge crossings of 3D surfaces (two surface edges passing through each
//! other with no vertex near a face), and corners that move more than g + h in one step.
#include <mpm/domains/particle_domains.h>

namespace mpm::domains {

struct SurfaceContactResult {
  std::size_t pairs = 0;     //!< vertex-face pairs within reach this step
  std::size_t contacts = 0;  //!< pairs that received an impulse
};

//! Applies the contact impulses to the corner velocities in domains.momentum (after
//! grid_to_corners and integrate_enriched) and adds the same changes to the FLIP increments in
//! domains.force; domains.mass are the corner masses of the step. `thickness` h > 0 [m]. Does
//! nothing without an enriched corner.
template <int dim>
SurfaceContactResult surface_contact(ParticleDomains<dim>& domains, double dt, double thickness, int sweeps = 8);

}  // namespace mpm::domains
