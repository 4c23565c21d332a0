#pragma once
//! The rest-state deviation of Zhu et al. (Dynamically Enriched MPM, Table 1): how far an
//! elastic body that came back to rest lies from its rest shape, after the rigid motion is
//! removed by shape matching (Mueller et al. 2005):
//!   R = rotation of the polar decomposition of A = sum_p m_p (x_p - xc)(X_p - Xc)^T,
//!   error = mean_p |R (X_p - Xc) + xc - x_p| / d,
//! xc, Xc the mass centres, d the diagonal of the rest shape's bounding box. Zero for any rigid
//! motion of the rest shape; transfer error that behaves like plasticity shows as a positive
//! error.
#include <mpm/core/types.h>

#include <vector>

namespace mpm::solid {

//! The rest shape X_p of particles at x_p with deformation gradients F_p in a body deformed
//! homogeneously about its mass centre: X_p = xc + F_p^-1 (x_p - xc) (a seeded body that starts
//! stretched, F = diag(stretch)). Error when a F_p is singular.
template <int dim>
std::vector<Vec<dim>> rest_shape(const std::vector<Vec<dim>>& x, const std::vector<Mat<dim>>& F,
                                 const std::vector<double>& mass);

//! The error above of positions x against the rest shape X (same sizes, mass weights m).
template <int dim>
double rest_state_error(const std::vector<Vec<dim>>& X, const std::vector<Vec<dim>>& x,
                        const std::vector<double>& mass);

}  // namespace mpm::solid
