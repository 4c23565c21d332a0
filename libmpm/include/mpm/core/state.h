#pragma once
//! The state a single-phase MPM pipeline advances: one particle set on one sparse grid.
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/particles.h>
#include <mpm/core/sparse_grid.h>
#include <mpm/core/transfer.h>

namespace mpm {

template <int dim>
struct MpmState {
  Particles<dim> particles;
  SparseGrid<dim> grid;
  ParticleBuckets<dim> buckets;
  Kernel kernel = QuadraticBSpline{};
  TransferScheme transfer;
  Vec<dim> gravity = Vec<dim>::Zero();  //!< [m/s^2]
  double time = 0.0;                    //!< [s]
  double dt = 0.0;                      //!< step being taken [s]
  double dt_limit = 1e300;              //!< largest step allowed now (frame end) [s]
  Index step = 0;
};

}  // namespace mpm
