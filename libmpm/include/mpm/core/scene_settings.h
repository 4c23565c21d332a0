#pragma once
//! The keys every scene shares: dimension, domain, grid, transfer, time, gravity and output.
//! See docs/user_guide.md (scene file reference) for units, defaults and ranges.
#include <mpm/core/config.h>
#include <mpm/core/kernels.h>
#include <mpm/core/transfer.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace mpm {

struct OutputSettings {
  bool particles = true;           //!< particles_NNNN.h5 + .xdmf per frame
  bool png = true;                 //!< preview_NNNN.png per frame
  std::string color_by = "speed";  //!< attribute coloured in previews
  int png_width = 640;             //!< [px]
  int checkpoint_every = 0;        //!< frames between checkpoints, 0 = by wall-clock time only
  double checkpoint_minutes = 10;  //!< wall-clock minutes between checkpoints (at a frame's end), 0 = off
  int checkpoints_kept = 2;        //!< the newest checkpoint_NNNN.h5 kept; older ones are removed
};

template <int dim>
struct SceneSettings {
  Vec<dim> domain_lo, domain_hi;  //!< [m]
  double dx = 0.0;                //!< grid spacing [m]
  //! Per axis: the domain is [lo, hi) with (hi - lo) / dx whole cells and no walls; what
  //! leaves through hi enters through lo (stages/periodic_boundary.h).
  std::array<bool, dim> periodic{};
  Kernel kernel;
  TransferScheme transfer;
  double end_time = 1.0;             //!< [s]
  double frame_dt = 0.02;            //!< output interval [s]
  double cfl = 0.4;                  //!< particle CFL number
  double wave_cfl = 0.5;             //!< elastic-wave Courant number
  double max_dt = 1e300;             //!< user upper bound on dt [s]
  int max_steps_per_frame = 200000;  //!< stops a run whose step collapsed instead of hanging
  Vec<dim> gravity;                  //!< [m/s^2]
  OutputSettings output;

  //! ceil(end_time / frame_dt), at most kMaxFrames (parse_scene_settings refuses more).
  int frame_count() const;
};

//! The most output frames a run may have: frame numbers are int in file names and checkpoints.
inline constexpr int kMaxFrames = 10000000;

//! The first position outside the domain box of `settings` (half-open [lo, hi) on periodic
//! axes): why ("a particle at (1.0025,
//! 0.2025) lies outside the domain (0, 0) - (1, 0.6)") and whether it lies below domain_lo;
//! an empty `why` when every position lies inside. Seeding checks bodies with it.
struct OutsideDomain {
  std::string why;
  bool below = false;
};
template <int dim>
OutsideDomain first_outside_domain(const SceneSettings<dim>& settings, const std::vector<Vec<dim>>& positions);

//! The interpolation kernel of `grid.kernel` (and `grid.particle_size` for uGIMP).
Kernel parse_kernel(const Config& scene);

//! Reads the top-level "dim" key (2 or 3) that selects the template instantiation.
int scene_dimension(const Config& scene);

//! The box and spacing of a scene that an app derives from its own keys.
template <int dim>
struct DerivedDomain {
  Vec<dim> lo, hi;
  double dx;
};

//! Reads the shared keys. With `derived`, the domain and grid.dx come from the app and the
//! keys 'domain' and 'grid.dx' are not read (so a scene that sets them gets "unknown key").
//! `periodic: [true, false]` (one flag per axis, default all false) makes axes periodic: the
//! domain must then hold a whole number (>= 4) of cells along them, and a `walls` map must
//! leave their faces open (x_min: open, x_max: open).
template <int dim>
SceneSettings<dim> parse_scene_settings(const Config& scene,
                                        const std::optional<DerivedDomain<dim>>& derived = std::nullopt);

}  // namespace mpm
