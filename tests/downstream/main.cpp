// Builds against the installed package: one P2G of a tiny particle set must conserve mass.
#include <mpm/core/transfer.h>
#include <mpm/solid/material.h>

#include <cmath>
#include <cstdio>

int main() {
  mpm::SparseGrid<2> grid(mpm::Vec<2>::Zero(), mpm::Vec<2>::Ones(), 0.1);
  mpm::Particles<2> particles;
  particles.push_back(mpm::Vec<2>(0.45, 0.52), mpm::Vec<2>(1.0, 0.0), 2.0, 1e-3, 0);
  mpm::ParticleBuckets<2> buckets;
  const mpm::Kernel kernel = mpm::QuadraticBSpline{};
  mpm::sort_into_buckets(particles, kernel, grid, buckets);
  mpm::particles_to_grid(particles, buckets, kernel, mpm::TransferScheme{}, grid);
  double mass = 0.0;
  for (double m : grid.mass) mass += m;
  const auto lame = mpm::constitutive::Lame::from_youngs_poisson(1e6, 0.3);
  std::printf("downstream: grid mass %.15g (expected 2), mu %.6g\n", mass, lame.mu);
  return std::fabs(mass - 2.0) < 1e-12 ? 0 : 1;
}
