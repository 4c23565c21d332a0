#include <mpm/io/png_preview.h>

#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>

#include "channel_sizes.h"

#include <png.h>
#include <Eigen/LU>  // determinant()

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace mpm::io {
namespace {

//! viridis (van der Walt & Smith, matplotlib 2015) at 9 equally spaced stops: perceptually
//! uniform and readable in grey scale and by colour-blind viewers.
constexpr Rgb kViridis[9] = {{68, 1, 84},    {71, 45, 123}, {59, 82, 139},  {44, 114, 142}, {33, 144, 140},
                             {39, 173, 129}, {93, 200, 99}, {170, 220, 50}, {253, 231, 37}};
constexpr Rgb kMagenta{255, 0, 255};
constexpr Rgb kFrame{64, 64, 64};
constexpr int kMaxPixels = 16384;  // per side; guards against a typo allocating gigabytes

//! Linear interpolation between the stops; t is clamped to [0, 1].
Rgb viridis(double t) {
  const double s = std::clamp(t, 0.0, 1.0) * 8.0;
  const int i = std::min(7, static_cast<int>(s));
  const double f = s - i;
  Rgb c;
  for (int k = 0; k < 3; ++k)
    c[k] = static_cast<std::uint8_t>(std::lround((1.0 - f) * kViridis[i][k] + f * kViridis[i + 1][k]));
  return c;
}

//! The attribute named by color_by, one value per particle: `speed` (|v|), `height` (y), or a
//! scalar that particle frames show under that name (io/particle_output.h): `material`, `mass`,
//! `J` = det F^E or `plastic` of solid particles, any extra channel marked `output`.
template <int dim>
std::vector<double> attribute(const Particles<dim>& p, const std::string& color_by) {
  std::vector<double> values(p.size());
  if (color_by == "speed" || color_by == "height") {
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = color_by == "speed" ? p.v[i].norm() : p.x[i][1];
    return values;
  }
  std::string known = "speed, height";
  bool found = false;
  p.for_each_channel([&](const ChannelInfo& info, const auto& channel) {
    using T = typename std::decay_t<decltype(channel)>::value_type;
    if constexpr (!std::is_same_v<T, Vec<dim>>) {  // frames show vectors as vectors, not one value
      if (!info.use.output) return;
      known += ", " + info.frame_name();
      if (info.frame_name() != color_by) return;
      found = true;
      for (std::size_t i = 0; i < values.size(); ++i) {
        if constexpr (std::is_same_v<T, Mat<dim>>)
          values[i] = channel[i].determinant();
        else
          values[i] = static_cast<double>(channel[i]);
      }
    }
  });
  verify<InputError>(found,
                     "png preview: color_by '" + color_by + "' is not a value of these particles (" + known + ")");
  return values;
}

//! The values mapped to the ends of the colour map.
std::array<double, 2> color_range(const std::vector<double>& values, const PreviewOptions& options) {
  if (options.color_range) {
    const auto [lo, hi] = *options.color_range;
    verify<InputError>(std::isfinite(lo) && std::isfinite(hi) && lo < hi,
                       "png preview: color_range must be finite with min < max");
    return {lo, hi};
  }
  std::array<double, 2> range{INFINITY, -INFINITY};
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    range[0] = std::min(range[0], v);
    range[1] = std::max(range[1], v);
  }
  return range;
}

class Image {
public:
  Image(int width, int height) : width_(width), height_(height), rgb_(3 * std::size_t(width) * height, 255) {}

  //! A disc of `radius` pixels centred at (px, py) (pixel units, y down), covering at least
  //! the pixel that holds the centre so that no particle vanishes.
  void splat(double px, double py, double radius, const Rgb& colour) {
    if (px + radius < 0 || px - radius > width_ || py + radius < 0 || py - radius > height_) return;
    const int i0 = std::max(0, static_cast<int>(std::floor(px - radius)));
    const int i1 = std::min(width_ - 1, static_cast<int>(std::floor(px + radius)));
    const int j0 = std::max(0, static_cast<int>(std::floor(py - radius)));
    const int j1 = std::min(height_ - 1, static_cast<int>(std::floor(py + radius)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double dx = i + 0.5 - px, dy = j + 0.5 - py;
        const bool holds_centre = i == static_cast<int>(std::floor(px)) && j == static_cast<int>(std::floor(py));
        if (dx * dx + dy * dy <= radius * radius || holds_centre) set(i, j, colour);
      }
  }

  void frame(const Rgb& colour) {
    for (int i = 0; i < width_; ++i) {
      set(i, 0, colour);
      set(i, height_ - 1, colour);
    }
    for (int j = 0; j < height_; ++j) {
      set(0, j, colour);
      set(width_ - 1, j, colour);
    }
  }

  //! Writes an 8-bit RGB PNG through libpng's simplified API, atomically.
  void write(const std::filesystem::path& path) const {
    AtomicFile out(path);
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    image.width = static_cast<png_uint_32>(width_);
    image.height = static_cast<png_uint_32>(height_);
    image.format = PNG_FORMAT_RGB;
    if (!png_image_write_to_file(&image, out.temp_path().c_str(), 0, rgb_.data(), 0, nullptr)) {
      const std::string reason = image.message;
      png_image_free(&image);
      throw IoError("cannot write '" + path.string() + "': libpng: " + reason);
    }
    out.commit();
  }

private:
  void set(int i, int j, const Rgb& colour) {
    std::copy(colour.begin(), colour.end(), rgb_.begin() + 3 * (std::size_t(j) * width_ + i));
  }

  int width_, height_;
  std::vector<std::uint8_t> rgb_;
};

}  // namespace

template <int dim>
void write_png_preview(const std::filesystem::path& path, const std::vector<PreviewLayer<dim>>& layers,
                       const PreviewOptions& options) {
  const auto& lo = options.domain_lo;
  const auto& hi = options.domain_hi;
  const double extent_x = hi[0] - lo[0], extent_y = hi[1] - lo[1];
  verify<InputError>(std::isfinite(extent_x) && std::isfinite(extent_y) && extent_x > 0 && extent_y > 0,
                     "png preview: the domain must have hi > lo in x and y");
  verify<InputError>(options.width_px >= 1 && options.width_px <= kMaxPixels,
                     "png preview: width_px must be in [1, " + std::to_string(kMaxPixels) + "]");
  const int width = options.width_px;
  const double height_exact = width * extent_y / extent_x;
  verify<InputError>(height_exact <= kMaxPixels, "png preview: the domain's aspect ratio gives an image taller than " +
                                                     std::to_string(kMaxPixels) + " px");
  const int height = std::max(1, static_cast<int>(std::lround(height_exact)));

  // One colour range over every layer coloured by the attribute, so that equal values look
  // equal in all of them.
  std::vector<std::vector<double>> values(layers.size());
  std::vector<double> all;
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const PreviewLayer<dim>& layer = layers[l];
    detail::verify_channel_sizes(*layer.particles, path);
    verify<InputError>(std::isfinite(layer.point_radius_px) && layer.point_radius_px >= 0,
                       "png preview: point_radius_px must be finite and >= 0");
    if (layer.colour) continue;
    values[l] = attribute(*layer.particles, options.color_by);
    all.insert(all.end(), values[l].begin(), values[l].end());
  }
  const auto [value_lo, value_hi] = color_range(all, options);

  Image image(width, height);
  const double scale_x = width / extent_x, scale_y = height / extent_y;
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const Particles<dim>& p = *layers[l].particles;
    // Painter's order: a particle with a non-finite position has no place in the image (and
    // would break the sort), so it is left out.
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.x[i].allFinite()) order.push_back(i);
    if constexpr (dim == 3)
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return p.x[a][2] < p.x[b][2]; });
    for (const std::size_t i : order) {
      Rgb colour = layers[l].colour ? *layers[l].colour : kMagenta;
      if (!layers[l].colour && std::isfinite(values[l][i])) {
        const double t = value_hi > value_lo ? (values[l][i] - value_lo) / (value_hi - value_lo) : 0.5;
        colour = viridis(t);
      }
      image.splat((p.x[i][0] - lo[0]) * scale_x, (hi[1] - p.x[i][1]) * scale_y, layers[l].point_radius_px, colour);
    }
  }
  image.frame(kFrame);
  image.write(path);
}

template <int dim>
void write_png_preview(const std::filesystem::path& path, const Particles<dim>& p, const PreviewOptions& options) {
  write_png_preview<dim>(path, {{&p, std::nullopt, options.point_radius_px}}, options);
}

template void write_png_preview<2>(const std::filesystem::path&, const Particles<2>&, const PreviewOptions&);
template void write_png_preview<3>(const std::filesystem::path&, const Particles<3>&, const PreviewOptions&);
template void write_png_preview<2>(const std::filesystem::path&, const std::vector<PreviewLayer<2>>&,
                                   const PreviewOptions&);
template void write_png_preview<3>(const std::filesystem::path&, const std::vector<PreviewLayer<3>>&,
                                   const PreviewOptions&);

}  // namespace mpm::io
