#pragma once
//! Inflow and outflow boundaries of channel and river scenes (docs/user_guide.md, "Inflow and
//! outflow"):
//!
//!   inflow:                      # optional
//!     face: x_min                # the face the stream enters through: x_min .. z_max
//!     velocity: [0.3, 0]         # U [m/s]; its largest component is normal to the face and
//!                                # points into the domain
//!     lo: [0, 0]                 # the inlet box [lo, hi] [m]: every grid node inside moves at U
//!     hi: [0.1, 0.1]             # (a fixed sticky collider); it starts within the open layer
//!                                # of the face and reaches at least one cell beyond it
//!     particles_per_cell: 4      # k^dim of the emitted lattice (default 4 in 2D, 8 in 3D)
//!   outflow:                     # optional
//!     face: x_max                # particles within wall_layer(kernel, dx) of it are removed
//!
//! A face with a flow boundary is open: `walls.<face>` must be absent or `open`, and its axis
//! must not be periodic. The stream
//! enters through the plane half a lattice spacing beyond the open layer of the inflow face
//! (particle_source.h), at the volume flux |U_n| A over the inlet section A; particles that
//! flow back out through the inflow face are removed like outflow.
#include <mpm/core/config.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/stages/particle_sink.h>
#include <mpm/core/stages/particle_source.h>
#include <mpm/geometry/collider.h>

#include <optional>
#include <string>
#include <vector>

namespace mpm::geometry {

//! One face of the domain box.
struct Face {
  int axis = 0;
  Side side = Side::lower;
};

//! "x_min" .. "z_max".
std::string face_name(const Face& face);

template <int dim>
struct Inflow {
  Face face;
  Vec<dim> velocity;           //!< U [m/s]
  Vec<dim> lo, hi;             //!< the inlet box [m]
  int particles_per_cell = 1;  //!< k^dim
};

template <int dim>
struct FlowBoundaries {
  std::optional<Inflow<dim>> inflow;
  std::optional<Face> outflow;
};

//! The optional `inflow` and `outflow` maps of `scene` for the domain and kernel of `settings`.
//! InputError (file, line, key, value) for an unknown face, a face closed by a wall or on a
//! periodic axis, both on the same face, a velocity that does not enter through its face, or an inlet box that leaves the
//! domain or does not reach past the open layer of its face.
template <int dim>
FlowBoundaries<dim> parse_flow_boundaries(const Config& scene, const SceneSettings<dim>& settings);

//! InputError at `at`'s key lo or hi unless the box [lo, hi] lies inside the domain of
//! `settings` (an inlet or an emitter: particles outside would stop the run at the next sort).
template <int dim>
void require_inside_domain(const Config& at, const Vec<dim>& lo, const Vec<dim>& hi,
                           const SceneSettings<dim>& settings);

//! Opens the walls of the flow faces and adds the inlet (a fixed box, sticky relative to U,
//! Motion::fixed) to `colliders`, so the boundary stage, the viscous solve and the pressure
//! projection all treat the inlet nodes as prescribed.
template <int dim>
void add_flow_boundaries(const FlowBoundaries<dim>& flow, ColliderSet<dim>& colliders);

//! The emitter of `inflow`: particles of volume V_p = dx^dim / particles_per_cell and mass
//! density * V_p [kg] enter the inlet box through the plane half a lattice spacing beyond the
//! open layer of the face.
template <int dim>
typename stages::ParticleSource<dim>::Settings inflow_source(const Inflow<dim>& inflow,
                                                             const SceneSettings<dim>& settings, double density);

//! The regions a sink removes: the open layer (wall_layer(kernel, dx)) of the outflow face and of
//! the inflow face, and everything beyond them; empty without flow boundaries.
template <int dim>
std::vector<stages::SinkRegion<dim>> flow_sink_regions(const FlowBoundaries<dim>& flow,
                                                       const SceneSettings<dim>& settings);

}  // namespace mpm::geometry
