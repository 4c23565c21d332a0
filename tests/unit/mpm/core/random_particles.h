#pragma once
// Test helper: n particles uniformly in the box [lo, hi) with random velocities in
// [-0.5, 0.5), masses in [0.5, 1.5), volume 1e-3 and random APIC matrices C in [-1, 1).
#include <mpm/core/particles.h>

#include <random>

namespace mpm::test {

template <int dim>
Particles<dim> random_cloud(std::size_t n, const Vec<dim>& lo, const Vec<dim>& hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Particles<dim> P;
  for (std::size_t p = 0; p < n; ++p) {
    Vec<dim> x, v;
    for (int a = 0; a < dim; ++a) {
      x[a] = lo[a] + (hi[a] - lo[a]) * u(rng);
      v[a] = u(rng) - 0.5;
    }
    P.push_back(x, v, 0.5 + u(rng), 1e-3, 0);
    for (int a = 0; a < dim * dim; ++a) P.C.back().data()[a] = 2.0 * u(rng) - 1.0;
  }
  return P;
}

}  // namespace mpm::test
