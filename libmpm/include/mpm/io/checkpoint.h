#pragma once
//! Restart files: every particle channel stored bit-exactly in HDF5, with the clock of the run.
//!
//! Datasets: x, v (N x dim); C, F (N x dim*dim, each matrix flattened column-major as Eigen
//! stores it); mass, volume0, plastic (N); material (N, uint16). Doubles are stored as IEEE
//! doubles, so a restarted run continues from the same bits. F and plastic have 0 rows when
//! the particles carry no deformation. Root attributes: format "mpm-checkpoint", version,
//! deformation (Particles::has_deformation(), which holds even for 0 particles) and the
//! CheckpointHeader fields. The file is replaced atomically (io/atomic_file.h).
//!
//! A state of several particle phases (the coupled fluid and sediment) stores each phase's
//! datasets in a group named after it ("fluid/x", ...) and its deformation flag in the root
//! attribute "<name>.deformation"; the unnamed phase "" uses the root, as above.
#include <mpm/core/particles.h>
#include <mpm/core/stage.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace mpm::io {

struct CheckpointHeader {
  int dim = 0;               //!< 2 or 3; save_checkpoint stores the dimension of its particles
  int frame = 0;             //!< last output frame written
  std::int64_t step = 0;     //!< time steps taken
  double time = 0.0;         //!< simulated time [s]
  double dt_previous = 0.0;  //!< last time step [s], so the dt limiter continues its history
  std::string scene_digest;  //!< digest of the resolved scene, to refuse a restart of another scene
  //! The pipeline's carried data (a pressure solver's warm start; mpm/core/stage.h), stored as
  //! datasets "stages/<name>" listed in the root attribute "stage_data".
  CarriedData stage_data;
};

//! One particle phase of a checkpoint: its name ("" for a single-phase state) and particles.
template <int dim>
struct CheckpointPhase {
  std::string name;
  const Particles<dim>* particles = nullptr;
};

template <int dim>
void save_checkpoint(const std::filesystem::path& path, const std::vector<CheckpointPhase<dim>>& phases,
                     const CheckpointHeader& header);
template <int dim>
void save_checkpoint(const std::filesystem::path& path, const Particles<dim>& p,
                     const CheckpointHeader& header) {
  save_checkpoint<dim>(path, {{"", &p}}, header);
}

//! Fills `header` from the file. Throws IoError for a missing, unreadable or corrupt file and
//! InputError for a file that is not a checkpoint or holds the other dimension.
//! Reads the phase `phase` ("" for a single-phase state); InputError when the file has no such
//! phase.
template <int dim>
Particles<dim> load_checkpoint(const std::filesystem::path& path, CheckpointHeader& header,
                               const std::string& phase = "");

}  // namespace mpm::io
