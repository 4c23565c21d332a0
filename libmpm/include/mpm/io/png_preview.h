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
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace mpm::io {

struct PreviewOptions {
  std::array<double, 3> domain_lo{0.0, 0.0, 0.0};  //!< [m]; the image shows [lo, hi] in x and y
  std::array<double, 3> domain_hi{1.0, 1.0, 1.0};  //!< [m]
  int width_px = 640;                              //!< the height follows from the aspect ratio of the domain
  //! "speed", "height" (y) or a scalar of the particle frames: "material", "J", "plastic", ...
  std::string color_by = "speed";
  double point_radius_px = 2.0;
  //! Attribute values mapped to the ends of the colour map; unset: min and max of the finite
  //! values in the frame (auto ranges make frames of a movie incomparable, so fix it for movies).
  std::optional<std::array<double, 2>> color_range;
};

//! An 8-bit RGB colour.
using Rgb = std::array<std::uint8_t, 3>;

//! One particle set of a picture of several phases. Layers are drawn in list order, each over
//! the ones before (so list the fluid before the grains it carries); a layer with a fixed
//! `colour` is drawn in it, the others are coloured by PreviewOptions::color_by over one
//! range shared by all of them.
template <int dim>
struct PreviewLayer {
  const Particles<dim>* particles = nullptr;
  std::optional<Rgb> colour;
  double point_radius_px = 2.0;
};

template <int dim>
void write_png_preview(const std::filesystem::path& path, const std::vector<PreviewLayer<dim>>& layers,
                       const PreviewOptions& options);

//! A single particle set, drawn with options.point_radius_px.
//! Throws InputError for invalid options (also for a color_by the particles do not carry, such
//! as J without the solid channels) and IoError when the file cannot be written.
template <int dim>
void write_png_preview(const std::filesystem::path& path, const Particles<dim>& p, const PreviewOptions& options);

}  // namespace mpm::io
