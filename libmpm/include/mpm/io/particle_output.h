#pragma once
//! Per-frame particle output for ParaView: one HDF5 file per frame, described by XDMF 3.
//!
//! particles_0007.h5 holds, for N particles (SI units), every channel marked `output`
//! (core/particles.h) under its frame name: a Vec channel as N x 3 (2D padded with z = 0 so that
//! ParaView shows it), a matrix channel as its determinant (N), a uint16 channel as int32 (N), a
//! double channel as it is (N). That is position [m] and velocity [m/s] (x and v), mass [kg],
//! volume0 [m^dim] and material (int32 index) for every particle set, J = det F^E and plastic
//! (the Drucker-Prager volume correction) for solid particles (solid/solid_channels.h); and the
//! derived speed = |v| [m/s]. Root attributes: time [s], frame, dim, run_id (the
//! run that wrote it, when given) and "attributes" (the
//! datasets besides position, one a line, in the order the XDMF lists them).
//! particles_0007.xdmf next to it describes the frame as a Polyvertex grid, and particles.xdmf
//! gathers the frames as a time series. All files are replaced atomically (io/atomic_file.h).
#include <mpm/core/particles.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace mpm::io {

//! "particles_0007.h5": the file name of a frame, as write_time_series_xdmf expects it. A
//! state of several phases writes one series per phase, named after it ("sediment_0007.h5").
std::string particle_file_name(int frame, const std::string& stem = "particles");

//! Writes h5_path and its sidecar (same stem, .xdmf); time in [s].
template <int dim>
void write_particles(const std::filesystem::path& h5_path, const Particles<dim>& p, double time, int frame,
                     const std::string& run_id = "");

//! Writes dir/<stem>.xdmf, a temporal collection of `frames` (frame number, time [s]). Each
//! frame's grid is described from dir/particle_file_name(frame, stem), which must exist.
void write_time_series_xdmf(const std::filesystem::path& dir, const std::vector<std::pair<int, double>>& frames,
                            const std::string& stem = "particles");

}  // namespace mpm::io
