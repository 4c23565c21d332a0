#pragma once
//! The per-particle state of a solid, declared as extra channels of a particle set
//! (core/particles.h) by the scenes that seed solid material, so that other phases carry none:
//!   F        Mat<dim>  elastic deformation gradient F^E (written to frames as J = det F^E)
//!   plastic  double    plastic state: the log volume correction of Tampubolon et al. 2017
//! Both are written to particle frames and stored in checkpoints.
//!
//! The accessors look a channel up by name (a short scan): a stage calls them once per run(),
//! outside its particle loops, never per particle.
#include <mpm/core/particles.h>

#include <vector>

namespace mpm::solid {

inline constexpr const char* kElasticF = "F";
inline constexpr const char* kPlastic = "plastic";

//! Declares F (= I) and plastic (= 0) for the particles present and every later one
//! (idempotent).
template <int dim>
void add_solid_channels(Particles<dim>& P) {
  P.template add_channel<Mat<dim>>(kElasticF, Mat<dim>::Identity(),
                                   {.output = true, .checkpoint = true, .output_name = "J"});
  P.template add_channel<double>(kPlastic, 0.0, {.output = true, .checkpoint = true});
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
