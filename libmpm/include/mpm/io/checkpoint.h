#pragma once
//! Restart files: every particle channel marked `checkpoint` (core/particles.h) stored
//! bit-exactly in HDF5, with the clock of the run.
//!
//! Format version 3. Each stored channel is a dataset named after it: a Vec channel N x dim, a
//! matrix channel N x dim*dim (flattened column-major as Eigen stores it), a double or uint16
//! channel N. Every particle set stores x, v, C, mass, volume0 and material; solid particles add
//! F and plastic (solid/solid_channels.h). Doubles are stored as IEEE doubles, so a restarted run
//! continues from the same bits. Root attributes: format "mpm-checkpoint", version, the
//! CheckpointHeader fields and, per phase, "particles" (N, which holds even for 0 particles) and
//! "channels" (the names of the stored channels, one a line). The file is replaced atomically
//! (io/atomic_file.h).
//!
//! Integrity: the root attribute "header_checksum" covers the header (clock, digests, run id, inputs,
//! stage data) and "<phase>.checksum" every byte of the phase's datasets, in order; loading
//! recomputes both and refuses a file whose datasets or header changed after it was written
//! (IoError naming the file and the part). "inputs" lists the files the scene read (meshes, level
//! sets) with the digest of their content, one "key<TAB>path<TAB>digest" a line.
//!
//! A state of several particle phases (the coupled fluid and sediment) stores each phase's
//! datasets in a group named after it ("fluid/x", ...) and its attributes as "<name>.particles"
//! and "<name>.channels"; the unnamed phase "" uses the root, as above.
//!
//! Loading fills a particle set whose channels the scene has declared already (seeding declares
//! them), so the file must store exactly the channels that set marks `checkpoint`: one missing
//! or one the set does not declare (the F of a solid in a fluid phase) means another scene.
#include <mpm/core/particles.h>
#include <mpm/core/stage.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace mpm::io {

//! A file a scene read (Config::input_file): its key, its path and the digest of its content.
struct InputFile {
  std::string key;
  std::string path;
  std::string digest;
  bool operator==(const InputFile&) const = default;
};

//! The digest of a file's content (16 hex digits); IoError when it cannot be read.
std::string file_digest(const std::filesystem::path& path);

struct CheckpointHeader {
  int dim = 0;                    //!< 2 or 3; save_checkpoint stores the dimension of its particles
  int frame = 0;                  //!< last output frame written
  std::int64_t step = 0;          //!< time steps taken
  double time = 0.0;              //!< simulated time [s]
  double dt_previous = 0.0;       //!< last time step [s], so the dt limiter continues its history
  std::string scene_digest;       //!< digest of the resolved scene, to refuse a restart of another scene
  std::string run_id;             //!< the run that wrote it (every output file of a run carries it)
  std::int64_t frame_step = 0;    //!< `step` at the end of `frame` (less than `step` when a stop came mid-frame)
  std::vector<InputFile> inputs;  //!< files the scene read, with the digest of their content
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

//! Writes the checkpoint; returns the checksum of its particle data (all phases; 16 hex digits),
//! which two runs share exactly when their particles are equal in every bit.
template <int dim>
std::string save_checkpoint(const std::filesystem::path& path, const std::vector<CheckpointPhase<dim>>& phases,
                            const CheckpointHeader& header);
template <int dim>
std::string save_checkpoint(const std::filesystem::path& path, const Particles<dim>& p,
                            const CheckpointHeader& header) {
  return save_checkpoint<dim>(path, {{"", &p}}, header);
}

//! Fills `header` and the particles of `into` (phase `phase`, "" for a single-phase state) from
//! the file: every channel of `into` marked `checkpoint` is read; the others get their initial
//! value. Throws IoError for a missing, unreadable or corrupt file and InputError for a file that
//! is not a checkpoint, holds the other dimension, has no such phase, lacks a channel of `into`
//! or stores one with the wrong shape, or stores a channel that `into` does not declare (the
//! messages name the file, the phase and the channel); IoError when a checksum does not match. `header` and `into` are left untouched
//! when it throws.
template <int dim>
void load_checkpoint(const std::filesystem::path& path, CheckpointHeader& header, Particles<dim>& into,
                     const std::string& phase = "");

}  // namespace mpm::io
