#pragma once
//! A coupled sediment-fluid scene from a scene file (coupled_scene.h; docs/coupling.md,
//! "Scene files"). Keys besides the shared ones (scene_settings.h) and walls/colliders
//! (collider_config.h):
//!
//!   fluid: {density: 1000, viscosity: 1.0e-3}  # fluid_scene.h; absent: a dry scene
//!   pressure: {solver: mgpcg}                  # fluid_scene.h, optional
//!   drag: {law: schiller_naumann, grain_diameter: 2.0e-4}   # drag_law.h; with both phases
//!   sediment:                  # absent: clear fluid
//!     density: 2650            # rho_s [kg/m^3] > 0
//!     youngs_modulus: 1.0e6    # optional: with it the sediment is a continuum and this map
//!     poisson_ratio: 0.3       #   holds the keys of material.h (hencky_stvk, drucker_prager,
//!     elasticity: hencky_stvk  #   ...); without it every particle is a discrete grain
//!     plasticity: {model: drucker_prager, friction_angle: 30}
//!     min_fluid_fraction: 0.35 # n_min in (0, 1], volume_fraction.h
//!     packing_fraction: 0.6    # default phi of the sediment bodies, (0, 1 - n_min]
//!     switching: {dilute_below: 0.2, dense_above: 0.45}   # optional, continuum only
//!                              #   (stages/reclassify_sediment.h); with bed_load also
//!                              #   rouse_number: 2.5, the suspension criterion (> 0)
//!   bodies:
//!     - phase: sediment        # sediment | fluid
//!       shape: box             # body_config.h: box | sphere | level_set, particles_per_cell,
//!       lo: [0, 0]             #   jitter, seed
//!       hi: [0.1, 0.2]
//!       packing_fraction: 0.62 # phi: grain volume per particle = phi V_p (default above)
//!       velocity: [0, 0]       # [m/s], default 0
//!     - {phase: fluid, shape: box, lo: [0, 0], hi: [0.4, 0.3]}
//!   emitters:                  # optional: streams entering through a box (particle_source.h)
//!     - phase: sediment        # sediment | fluid
//!       lo: [0.1, 0.3]         # the box [m]; particles enter through its upstream face
//!       hi: [0.12, 0.32]
//!       velocity: [0, -0.5]    # [m/s], not zero
//!       particles_per_cell: 4  # k^dim of the emitted lattice
//!       packing_fraction: 0.3  # sediment: phi of the stream (default sediment.packing_fraction)
//!       start: 0               # [s], default 0
//!       stop: 1.0              # [s], default never
//!   inflow/outflow             # flow_boundary_config.h: the inflow is one more fluid emitter,
//!                              # the outflow removes the particles of both phases
//!
//! A fluid body fills the pores of the sediment bodies it overlaps: its particles inside one
//! (in a sub-cell of that body's seeding lattice that holds a grain particle) carry fluid
//! fraction 1 - phi, the others 1 (as the settling column does). Sediment bodies do not
//! overlap one another.
#include <coupling/coupled_scene.h>
#include <mpm/core/config.h>

namespace coupling {

//! The `sediment` map (keys above, without the bodies).
template <int dim>
SedimentPhase<dim> parse_sediment_phase(const mpm::Config& sediment);

//! Reads the keys above and seeds the bodies. InputError (file, line, key, value, range) on a
//! bad value, a `periodic` axis (not supported by the coupled stages), an unknown phase, law or key type, a body of a phase the scene lacks, or a
//! scene with both phases and no `drag`.
template <int dim>
CoupledScene<dim> load_coupled_scene(const mpm::Config& scene);

}  // namespace coupling
