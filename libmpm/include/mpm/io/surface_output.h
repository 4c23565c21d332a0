#pragma once
//! Per-frame output of the surface of bodies with particle domains (domains/particle_domains.h),
//! for ParaView: the deformed boundary of the domains, which stays closed however the body
//! deforms.
//!
//! surface_0007.h5 holds `points` (the N domain corners [m], N x 3, 2D padded with z = 0) and
//! `faces` (M x 2 int32 corner indices of the boundary edges in 2D, M x 4 of the boundary
//! quadrilaterals in 3D, oriented outward). Root attributes: time [s], frame, run_id.
//! surface_0007.xdmf describes it (Polyline or Quadrilateral topology); surface.xdmf gathers the
//! frames as a time series. Files are replaced atomically (io/atomic_file.h).
//!
//! Bodies seeded from a triangle mesh also carry that mesh embedded in their domains
//! (ParticleDomains::embedded_triangles): mesh_0007.h5 holds its deformed `points` (N x 3 [m])
//! and `triangles` (M x 3 int32), with mesh_0007.xdmf (Triangle topology) and mesh.xdmf.
#include <mpm/domains/particle_domains.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace mpm::io {

template <int dim>
void write_surface(const std::filesystem::path& h5_path, const domains::ParticleDomains<dim>& domains, double time,
                   int frame, const std::string& run_id = "");

//! Writes dir/surface.xdmf over the frames (frame, time [s]); each dir/surface_NNNN.h5 must exist.
template <int dim>
void write_surface_time_series(const std::filesystem::path& dir, const std::vector<std::pair<int, double>>& frames);

//! The embedded mesh at the corners' current positions (embedded_position).
template <int dim>
void write_embedded_mesh(const std::filesystem::path& h5_path, const domains::ParticleDomains<dim>& domains,
                         double time, int frame, const std::string& run_id = "");

//! Writes dir/mesh.xdmf over the frames; each dir/mesh_NNNN.h5 must exist.
void write_embedded_mesh_time_series(const std::filesystem::path& dir,
                                     const std::vector<std::pair<int, double>>& frames);

}  // namespace mpm::io
