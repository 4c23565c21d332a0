#pragma once
//! The gap between two bodies of particles: how close a grid's contact lets them come.
//!
//! On one background grid two bodies touch through the nodes they share, so they stop, and
//! rebound, while their particles are still some distance apart; that distance shrinks with the
//! cell size (the adaptive GIMP paper's Fig. 4: the coarse grid's jellos bounce a fraction of a
//! cell apart, the fine and the adaptive grids' almost touch). Each particle is the ball
//! inscribed in the cube of its reference volume (radius r_p = (V_p^0)^(1/dim) / 2, half the
//! width of its lattice cell), deformed by its F into the ellipsoid F_p B(r_p), whose extent
//! along the unit vector n is r_p |F_p^T n| (its support function). The gap is
//!   g = min over p in A, q in B of |x_q - x_p| - r_p |F_p^T n| - r_q |F_q^T n|,  n = (x_q - x_p) / |x_q - x_p|,
//! the gap between the two ellipsoids' shadows on their line of centres: a lower bound of the
//! distance between them, equal to it for balls (F a scaled rotation) and for axis-aligned
//! ellipsoids whose centres lie on one axis, as across two lattices that meet face to face (the
//! distance between the faces: 0 for two lattices seeded side by side; with F the faces follow a
//! compression across the contact).
//! Negative where the shadows overlap, as they do wherever the ellipsoids do.
//!
//! Only pairs within `reach` matter: the bodies' bounding boxes first (a step far from contact
//! costs one pass over the particles), then B's particles near A's box in cells, and A's near B's
//! box, nearest first, each searching the cells within the best gap found so far plus the radii.
#include <mpm/core/particles.h>

#include <cstdint>
#include <vector>

namespace mpm::geometry {

//! g of the particles of material `a` and those of material `b` (a != b), or `reach` [m] > 0 when no pair
//! comes closer than that (also when either body has no particle); `reach` finite. Throws
//! NumericalError where a position or F of either body is not finite. `F`: each particle's
//! deformation gradient (an elastic body's F^E), or nullptr for the undeformed balls (F = I).
template <int dim>
double body_gap(const Particles<dim>& particles, std::uint16_t a, std::uint16_t b, double reach,
                const std::vector<Mat<dim>>* F = nullptr);

}  // namespace mpm::geometry
