#pragma once
//! The particles of one entry of a scene's `bodies` list (shared by the solid and the fluid):
//!
//!   - shape: box                 # box (lo, hi) | sphere (center, radius) | level_set (the
//!     lo: [0.2, 0.2]             #   keys of a level-set collider: file, voxel_size, ...)
//!     hi: [0.4, 0.4]
//!     particles_per_cell: 4      # k^dim, default 4 in 2D and 8 in 3D
//!     jitter: 0.0                # [0, 1) of the lattice spacing
//!     seed: 1                    # of the jitter
//!
//! The phase-specific keys (material, velocity, ...) are read by the caller.
#include <mpm/core/config.h>
#include <mpm/core/scene_settings.h>

#include <string>
#include <vector>

namespace mpm::geometry {

//! The `particles_per_cell` key of `cfg` (default 4 in 2D, 8 in 3D); must be k^dim.
template <int dim>
int particles_per_cell(const Config& cfg);

template <int dim>
struct BodyParticles {
  std::vector<Vec<dim>> x;  //!< positions on the seeding lattice inside the shape [m]
  double volume = 0.0;      //!< volume of each particle, dx^dim / particles_per_cell [m^dim]
};

//! Seeds the shape of `body`; `shapes` lists the shapes the caller accepts. Fails through
//! Config (file, line, key, value) when the body holds no particle or leaves the domain.
template <int dim>
BodyParticles<dim> seed_body_shape(const Config& body, const SceneSettings<dim>& settings,
                                   const std::vector<std::string>& shapes = {"box", "sphere", "level_set"});

}  // namespace mpm::geometry
