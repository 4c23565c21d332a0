#include <mpm/core/number_text.h>
#include <mpm/geometry/seeding.h>

#include <mpm/core/error.h>
#include <mpm/core/memory_budget.h>
#include <mpm/geometry/signed_distance.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace mpm::geometry {

namespace {

//! Lattice points a single call may visit: beyond that a unit mistake is more likely than a scene.
constexpr double kMaxLatticePoints = 4e9;

//! Uniform in [0, 1) from the top 53 bits of one draw: the same numbers on every platform,
//! which std::uniform_real_distribution does not promise.
double unit_uniform(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

}  // namespace

template <int dim>
int lattice_points_per_axis(int particles_per_cell) {
  const int k = int(std::lround(std::pow(double(particles_per_cell), 1.0 / dim)));
  verify<InputError>(particles_per_cell > 0 && ipow(k, dim) == particles_per_cell,
                     "particles per cell must be k^" + std::to_string(dim) + " for an integer k >= 1 (" +
                         (dim == 2 ? "1, 4, 9, 16, ..." : "1, 8, 27, 64, ...") + "), got " +
                         std::to_string(particles_per_cell));
  return k;
}

template <int dim>
double particle_volume(double dx, int particles_per_cell) {
  return std::pow(dx, dim) / particles_per_cell;
}

template <int dim>
std::vector<Vec<dim>> seed_lattice(const Vec<dim>& lo, const Vec<dim>& hi, double dx, int particles_per_cell,
                                   double jitter, std::uint64_t seed,
                                   const std::function<bool(const Vec<dim>&)>& inside) {
  verify<InputError>(std::isfinite(dx) && dx > 0.0, "seeding: dx must be > 0, got " + number_text(dx));
  verify<InputError>(jitter >= 0.0 && jitter < 1.0, "seeding: jitter must be in [0, 1), got " + number_text(jitter));
  const double h = dx / lattice_points_per_axis<dim>(particles_per_cell);

  // Lattice indices i with lo <= (i + 1/2) h < hi.
  Vec<dim> first_index, end_index;
  double candidates = 1.0;
  for (int a = 0; a < dim; ++a) {
    first_index[a] = std::ceil(lo[a] / h - 0.5);
    end_index[a] = std::max(first_index[a], std::ceil(hi[a] / h - 0.5));
    candidates *= end_index[a] - first_index[a];
  }
  verify<InputError>(first_index.cwiseAbs().maxCoeff() < 2e9 && end_index.cwiseAbs().maxCoeff() < 2e9,
                     "seeding: the body lies beyond 2e9 sub-spacings from the origin; check its bounds");
  verify<InputError>(candidates <= kMaxLatticePoints, "seeding: " + number_text(candidates) +
                                                          " lattice points (at most " + number_text(kMaxLatticePoints) +
                                                          "); check dx and the extent of the body");
  if (const std::string why = memory_shortfall(candidates * kBytesPerParticle<dim>); !why.empty())
    throw InputError("seeding: up to " + number_text(candidates) + " particles at grid spacing dx = " +
                     number_text(dx) + " m, " + std::to_string(particles_per_cell) + " per cell, need " + why +
                     ": coarsen the grid or lower particles_per_cell");
  const IVec<dim> first = first_index.template cast<int>(), end = end_index.template cast<int>();
  std::vector<Vec<dim>> points;
  if (candidates == 0.0) return points;

  std::mt19937_64 rng(seed);
  IVec<dim> i = first;
  while (true) {
    const Vec<dim> x = (i.template cast<double>().array() + 0.5).matrix() * h;
    if (inside(x)) {
      Vec<dim> p = x;
      if (jitter > 0.0)
        for (int a = 0; a < dim; ++a) p[a] += jitter * h * (unit_uniform(rng) - 0.5);
      points.push_back(p);
    }
    // Odometer over the index box, axis 0 fastest.
    int a = 0;
    for (; a < dim; ++a) {
      if (++i[a] < end[a]) break;
      i[a] = first[a];
    }
    if (a == dim) return points;
  }
}

template <int dim>
std::vector<Vec<dim>> seed_box(const Vec<dim>& lo, const Vec<dim>& hi, double dx, int particles_per_cell, double jitter,
                               std::uint64_t seed) {
  return seed_lattice<dim>(lo, hi, dx, particles_per_cell, jitter, seed, [](const Vec<dim>&) { return true; });
}

template <int dim>
std::vector<Vec<dim>> seed_sphere(const Vec<dim>& center, double radius, double dx, int particles_per_cell,
                                  double jitter, std::uint64_t seed) {
  const Sphere<dim> sphere(center, radius);
  const Vec<dim> r = Vec<dim>::Constant(radius);
  return seed_lattice<dim>(center - r, center + r, dx, particles_per_cell, jitter, seed,
                           [&](const Vec<dim>& x) { return sphere.phi(x) < 0.0; });
}

template <int dim>
std::vector<Vec<dim>> seed_level_set(const LevelSetShape<dim>& shape, double dx, int particles_per_cell, double jitter,
                                     std::uint64_t seed) {
  const BoundingBox& box = shape.level_set().bounding_box();
  return seed_lattice<dim>(box.lo.template head<dim>(), box.hi.template head<dim>(), dx, particles_per_cell, jitter,
                           seed, [&](const Vec<dim>& x) { return shape.inside(x); });
}

#define MPM_INSTANTIATE_SEEDING(dim)                                                                                  \
  template int lattice_points_per_axis<dim>(int);                                                                     \
  template double particle_volume<dim>(double, int);                                                                  \
  template std::vector<Vec<dim>> seed_lattice<dim>(const Vec<dim>&, const Vec<dim>&, double, int, double,             \
                                                   std::uint64_t, const std::function<bool(const Vec<dim>&)>&);       \
  template std::vector<Vec<dim>> seed_box<dim>(const Vec<dim>&, const Vec<dim>&, double, int, double, std::uint64_t); \
  template std::vector<Vec<dim>> seed_sphere<dim>(const Vec<dim>&, double, double, int, double, std::uint64_t);       \
  template std::vector<Vec<dim>> seed_level_set<dim>(const LevelSetShape<dim>&, double, int, double, std::uint64_t);
MPM_INSTANTIATE_SEEDING(2)
MPM_INSTANTIATE_SEEDING(3)
#undef MPM_INSTANTIATE_SEEDING

}  // namespace mpm::geometry
