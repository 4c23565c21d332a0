#include <coupling/bed_profile.h>
#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>

namespace coupling {

template <int dim>
BedProfile<dim>::BedProfile(const mpm::SceneSettings<dim>& settings, double packing)
    : lo_(settings.domain_lo), dx_(settings.dx), packing_(packing) {
  mpm::verify<mpm::InputError>(packing > 0.0 && packing < 1.0, "bed profile: packing fraction outside (0, 1)");
  for (int a = 0; a < dim; ++a)
    counts_[a] = a == 1 ? 1 : std::max(1, static_cast<int>(std::ceil((settings.domain_hi[a] - lo_[a]) / dx_)));
}

template <int dim>
std::int64_t BedProfile<dim>::column_count() const {
  return counts_.template cast<std::int64_t>().prod();
}

template <int dim>
std::vector<double> BedProfile<dim>::heights(const mpm::Particles<dim>& grains) const {
  std::vector<double> h(static_cast<std::size_t>(column_count()), 0.0);
  const double area = std::pow(dx_, dim - 1);
  for (std::size_t p = 0; p < grains.size(); ++p)
    if (const std::int64_t c = column(grains.x[p]); c >= 0)
      h[static_cast<std::size_t>(c)] += grains.volume0[p] / (area * packing_);
  return h;
}

template <int dim>
std::int64_t BedProfile<dim>::column(const mpm::Vec<dim>& x) const {
  std::int64_t c = 0;
  for (int a = dim - 1; a >= 0; --a) {
    if (a == 1) continue;
    const double i = std::floor((x[a] - lo_[a]) / dx_);
    if (!(i >= 0 && i < counts_[a])) return -1;
    c = c * counts_[a] + static_cast<std::int64_t>(i);
  }
  return c;
}

template <int dim>
mpm::Vec<dim> BedProfile<dim>::centre(std::int64_t c) const {
  mpm::Vec<dim> x = mpm::Vec<dim>::Zero();
  for (int a = 0; a < dim; ++a) {
    if (a == 1) continue;
    x[a] = lo_[a] + (static_cast<double>(c % counts_[a]) + 0.5) * dx_;
    c /= counts_[a];
  }
  return x;
}

template <int dim>
std::pair<double, double> BedProfile<dim>::change(const std::vector<double>& h0, const std::vector<double>& h,
                                                  const mpm::Vec<dim>& lo, const mpm::Vec<dim>& hi) const {
  double drop = 0.0, rise = 0.0;
  for (std::size_t c = 0; c < h.size(); ++c) {
    const mpm::Vec<dim> x = centre(static_cast<std::int64_t>(c));
    bool inside = true;
    for (int a = 0; a < dim; ++a)
      if (a != 1) inside = inside && x[a] >= lo[a] && x[a] <= hi[a];
    if (!inside) continue;
    drop = std::max(drop, h0[c] - h[c]);
    rise = std::max(rise, h[c] - h0[c]);
  }
  return {drop, rise};
}

template class BedProfile<2>;
template class BedProfile<3>;

}  // namespace coupling
