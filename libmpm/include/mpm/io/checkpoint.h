#pragma once
//! Restart files: every particle channel stored bit-exactly in HDF5, with the clock of the run.
//!
//! Datasets: x, v (N x dim); C, F (N x dim*dim, each matrix flattened column-major as Eigen
//! stores it); mass, volume0, plastic (N); material (N, uint16). Doubles are stored as IEEE
//! doubles, so a restarted run continues from the same bits. F and plastic have 0 rows when
//! the particles carry no deformation. Root attributes: format "mpm-checkpoint", version,
//! deformation (Particles::has_deformation(), which holds even for 0 particles) and the
//! CheckpointHeader fields. The file is replaced atomically (io/atomic_file.h).
#include <mpm/core/particles.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace mpm::io {

struct CheckpointHeader {
  int dim = 0;               //!< 2 or 3; save_checkpoint stores the dimension of its particles
  int frame = 0;             //!< last output frame written
  std::int64_t step = 0;     //!< time steps taken
  double time = 0.0;         //!< simulated time [s]
  double dt_previous = 0.0;  //!< last time step [s], so the dt limiter continues its history
  std::string scene_digest;  //!< digest of the resolved scene, to refuse a restart of another scene
};

template <int dim>
void save_checkpoint(const std::filesystem::path& path, const Particles<dim>& p,
                     const CheckpointHeader& header);

//! Fills `header` from the file. Throws IoError for a missing, unreadable or corrupt file and
//! InputError for a file that is not a checkpoint or holds the other dimension.
template <int dim>
Particles<dim> load_checkpoint(const std::filesystem::path& path, CheckpointHeader& header);

}  // namespace mpm::io
