#pragma once
//! PNG snapshot of the particles, for a quick look at a run without ParaView.
//!
//! Orthographic splats on a white background inside a thin frame drawn at the domain boundary:
//! x maps to the right and y up. In 3D the view looks along -z: particles are drawn in order of
//! increasing z, so the nearer one (larger z) covers the farther. Colours follow viridis; a
//! particle whose attribute is NaN or infinite is drawn magenta. The file is replaced
//! atomically (io/atomic_file.h).
#include <mpm/core/particles.h>

#include <array>
#include <filesystem>
#include <optional>
#include <string>

namespace mpm::io {

struct PreviewOptions {
  std::array<double, 3> domain_lo{0.0, 0.0, 0.0};  //!< [m]; the image shows [lo, hi] in x and y
  std::array<double, 3> domain_hi{1.0, 1.0, 1.0};  //!< [m]
  int width_px = 640;              //!< the height follows from the aspect ratio of the domain
  std::string color_by = "speed";  //!< "speed", "material", "J", "plastic" or "height" (y)
  double point_radius_px = 2.0;
  //! Attribute values mapped to the ends of the colour map; unset: min and max of the finite
  //! values in the frame (auto ranges make frames of a movie incomparable, so fix it for movies).
  std::optional<std::array<double, 2>> color_range;
};

//! Throws InputError for invalid options (also for J or plastic without deformation) and
//! IoError when the file cannot be written.
template <int dim>
void write_png_preview(const std::filesystem::path& path, const Particles<dim>& p,
                       const PreviewOptions& options);

}  // namespace mpm::io
