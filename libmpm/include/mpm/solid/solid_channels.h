#pragma once
//! The per-particle state of a solid, declared as extra channels of a particle set
//! (core/particles.h) by the scenes that seed solid material, so that other phases carry none:
//!   F        Mat<dim>  elastic deformation gradient F^E (written to frames as J = det F^E)
//!   plastic  double    plastic state: the log volume correction of Tampubolon et al. 2017
//! Both are written to particle frames and stored in checkpoints. The explicit solver of a
//! scene with plastic materials adds
//!   stress_cache  Mat<dim>  the Kirchhoff stress tau(F^E) that the return map computed from
//!                           its own SVD of F^E, so that the next step's forces need no second
//!                           SVD; NaN where unknown. Stored in checkpoints (a restart continues
//!                           bit-identically), not written to frames. Whoever changes F^E other
//!                           than the return map sets the entry anew or to NaN (a merge of
//!                           particles does, the channel being `derived`).
//! A scene with a dilatant material (Drucker-Prager with a dilatancy coefficient) adds
//!   rest_packing  double  phi_r, the grains' volume fraction at F^E = I: the packing is
//!                         phi_r / det F^E. Set by the scene's seeding (a body's packing
//!                         fraction), kept by the return map (drucker_prager.h); written to
//!                         frames and stored in checkpoints.
//!
//! The accessors look a channel up by name (a short scan): a stage calls them once per run(),
//! outside its particle loops, never per particle.
#include <mpm/core/particles.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace mpm::solid {

inline constexpr const char* kElasticF = "F";
inline constexpr const char* kPlastic = "plastic";
inline constexpr const char* kStressCache = "stress_cache";
inline constexpr const char* kRestPacking = "rest_packing";

//! Declares F (= I) and plastic (= 0) for the particles present and every later one
//! (idempotent).
template <int dim>
void add_solid_channels(Particles<dim>& P) {
  P.template add_channel<Mat<dim>>(kElasticF, Mat<dim>::Identity(),
                                   {.output = true, .checkpoint = true, .output_name = "J"});
  P.template add_channel<double>(kPlastic, 0.0, {.output = true, .checkpoint = true});
}

//! Declares stress_cache (all unknown) for the particles present and every later one
//! (idempotent).
template <int dim>
void add_stress_cache(Particles<dim>& P) {
  P.template add_channel<Mat<dim>>(kStressCache, Mat<dim>::Constant(std::numeric_limits<double>::quiet_NaN()),
                                   {.checkpoint = true, .derived = true});
}

//! Declares rest_packing (unknown, NaN) for the particles present and every later one
//! (idempotent). The return map starts a particle of unknown packing at its material's critical
//! packing (no dilatancy).
template <int dim>
void add_rest_packing(Particles<dim>& P) {
  P.template add_channel<double>(kRestPacking, std::numeric_limits<double>::quiet_NaN(),
                                 {.output = true, .checkpoint = true});
}

//! The rest packing, or nullptr when the particles carry none.
template <int dim>
std::vector<double>* rest_packing(Particles<dim>& P) {
  return P.template find_channel<double>(kRestPacking);
}

//! The stress cache, or nullptr when the particles carry none.
template <int dim>
std::vector<Mat<dim>>* stress_cache(Particles<dim>& P) {
  return P.template find_channel<Mat<dim>>(kStressCache);
}
template <int dim>
const std::vector<Mat<dim>>* stress_cache(const Particles<dim>& P) {
  return P.template find_channel<Mat<dim>>(kStressCache);
}

//! Whether a stress_cache entry holds a stress (it is NaN where unknown).
template <int dim>
bool known_stress(const Mat<dim>& tau) {
  return !std::isnan(tau(0, 0));
}

//! F^E of every particle; Error when add_solid_channels was not called.
template <int dim>
std::vector<Mat<dim>>& elastic_F(Particles<dim>& P) {
  return P.template channel<Mat<dim>>(kElasticF);
}
template <int dim>
const std::vector<Mat<dim>>& elastic_F(const Particles<dim>& P) {
  return P.template channel<Mat<dim>>(kElasticF);
}

//! The plastic state of every particle; Error when add_solid_channels was not called.
template <int dim>
std::vector<double>& plastic_state(Particles<dim>& P) {
  return P.template channel<double>(kPlastic);
}
template <int dim>
const std::vector<double>& plastic_state(const Particles<dim>& P) {
  return P.template channel<double>(kPlastic);
}

}  // namespace mpm::solid
