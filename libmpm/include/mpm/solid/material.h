#pragma once
//! A solid material of a scene: density, elasticity and plasticity, read from its YAML map.
//!
//!   name: sand                 # text, default "material"
//!   density: 1600              # [kg/m^3] > 0
//!   youngs_modulus: 3.5e7      # [Pa] > 0
//!   poisson_ratio: 0.3         # in (-1, 0.5)
//!   elasticity: hencky_stvk    # fixed_corotated (default) | neo_hookean | hencky_stvk
//!   plasticity:                # optional
//!     model: drucker_prager    # none (default) | drucker_prager | von_mises | snow
//!     friction_angle: 30       # [deg] in [0, 90), Drucker-Prager, default 30
//!     cohesion: 0              # [Pa] >= 0, Drucker-Prager, default 0
//!     yield_stress: 1e5        # [Pa] > 0, von Mises, required
//!     critical_compression: 2.5e-2  # snow: theta_c in (0, 1)
//!     critical_stretch: 7.5e-3      # snow: theta_s > 0
//!     hardening: 10                 # snow: xi >= 0
//!
//! Drucker-Prager and von Mises need hencky_stvk elasticity: both return maps are closed-form in
//! Hencky strain (Gao et al. 2017 sec. 4.2 uses eq. 7), and parsing rejects any other pairing.
//! Snow (Stomakhin et al. 2013) takes any elasticity.
#include <mpm/constitutive/elastic_model.h>
#include <mpm/constitutive/lame.h>
#include <mpm/core/config.h>
#include <mpm/core/types.h>
#include <mpm/plasticity/plasticity_model.h>

#include <string>

namespace mpm {

template <int dim>
struct Material {
  std::string name;
  double density = 0.0;  //!< [kg/m^3]
  constitutive::Lame lame;
  constitutive::ElasticModel<dim> elastic;
  plasticity::PlasticityModel<dim> plasticity;

  //! P-wave speed sqrt((lambda + 2 mu) / density) [m/s], the elastic limit of the time step.
  double wave_speed() const;
  //! Elastic energy density psi(F) [J/m^3] of one particle in the plastic state `plastic`
  //! (visits the model; not for hot loops).
  double energy(const Mat<dim>& F, double plastic = 0.0) const;
  //! Kirchhoff stress tau = P F^T [Pa] of one particle (visits the model; not for hot loops).
  Mat<dim> kirchhoff(const Mat<dim>& F, double plastic = 0.0) const;
  //! The factor of the elastic moduli in the plastic state `plastic` (snow hardening; else 1).
  double modulus_scale(double plastic) const;
};

//! Reads and validates a material map (keys above); throws InputError with the key's position.
template <int dim>
Material<dim> parse_material(const Config& cfg);

}  // namespace mpm
