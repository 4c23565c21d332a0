#pragma once
//! Lamé parameters of an isotropic solid.
//!
//! 2D scenes use the same (plane-strain) values as 3D: the 2D models are the 3D ones restricted
//! to in-plane deformation, so a material keeps its Young's modulus and Poisson ratio across
//! dimensions.

namespace mpm::constitutive {

struct Lame {
  double mu = 0.0;      //!< shear modulus [Pa]
  double lambda = 0.0;  //!< first Lamé parameter [Pa]

  //! From Young's modulus E [Pa] > 0 and Poisson ratio nu in (-1, 0.5) (validated by the caller).
  static Lame from_youngs_poisson(double E, double nu) {
    return {E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))};
  }

  //! P-wave modulus lambda + 2 mu [Pa]: the fastest elastic wave is sqrt(M / rho), which bounds
  //! the explicit time step.
  double p_wave_modulus() const { return lambda + 2.0 * mu; }
};

}  // namespace mpm::constitutive
