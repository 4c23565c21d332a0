#pragma once
//! Collision objects of a scene file.
//!
//!   colliders:                       # optional list, applied in this order
//!     - type: half_space             # point, normal (solid on the side opposite to normal)
//!       point: [0, 0.1]
//!       normal: [0, 1]
//!       contact: separate            # sticky | slip | separate (default)
//!       friction: 0.3                # Coulomb mu >= 0, separate contact only (default 0)
//!       velocity: [0, 0]             # [m/s], the obstacle translates (default at rest)
//!     - {type: box, lo: [0.4, 0.2], hi: [0.6, 0.3]}
//!     - {type: sphere, center: [0.5, 0.5], radius: 0.1}
//!     - {type: cylinder, point: [0.5, 0.5, 0], axis: [0, 0, 1], radius: 0.05, half_length: 0.2}
//!                                    # 3D; half_length optional (infinite); in 2D only point and
//!                                    # radius (the axis is out of plane)
//!     - type: level_set              # file: .vdb (grid_name optional) or .obj/.stl (voxel_size
//!       file: plate.obj              # [m] required, half_width [voxels] >= 3, default 3);
//!       voxel_size: 0.005            # a relative path is relative to the scene file;
//!       slice_z: 0.3                 # 2D only: the section plane z = slice_z [m] (default 0)
//!   walls:                           # optional: the faces of the domain box
//!     contact: separate              # for every wall (default separate)
//!     friction: 0.2                  # (default 0)
//!     thickness: 0.1                 # boundary layer [m] (default: wall_layer(kernel, dx),
//!                                    # (support - 1) dx, so no stencil leaves the grid)
//!     y_max: open                    # per face x_min .. z_max: sticky | slip | separate | open
//!
//! Every error is an InputError from Config (file, line, key path, value, accepted range).
#include <mpm/core/config.h>
#include <mpm/core/types.h>
#include <mpm/geometry/collider.h>

namespace mpm::geometry {

//! The `contact` and `friction` keys of a map (a collider's, the walls', or a phase's own
//! contact with a collider in a coupled scene).
Contact parse_contact(const Config& c);

//! The level set of an entry with keys file (.vdb, .obj or .stl; relative to the scene file),
//! voxel_size and half_width (meshes), grid_name (.vdb) and slice_z (2D). Shared by
//! `type: level_set` colliders and `shape: level_set` bodies.
template <int dim>
LevelSetShape<dim> parse_level_set(const Config& entry);

//! One entry of `colliders:`.
template <int dim>
Collider<dim> parse_collider(const Config& entry);

//! The `walls:` map for the domain box [domain_lo, domain_hi]; `default_thickness` [m] applies
//! when the map has no `thickness` key.
template <int dim>
DomainWalls<dim> parse_walls(const Config& walls, const Vec<dim>& domain_lo, const Vec<dim>& domain_hi,
                             double default_thickness);

//! The `colliders:` list and the `walls:` map of `scene` (the map that holds both keys).
template <int dim>
ColliderSet<dim> parse_colliders(const Config& scene, const Vec<dim>& domain_lo, const Vec<dim>& domain_hi,
                                 double default_wall_thickness);

}  // namespace mpm::geometry
