#pragma once
//! Per-frame output of an adaptive grid's leaves for ParaView (the refinement as a mesh).
//!
//! cells_0007.h5 holds, for N leaves: `points` (N 2^dim x 3 corner positions [m], each leaf its
//! own corners, 2D padded with z = 0), `cells` (N x 2^dim int32 corner indices in VTK order:
//! quadrilaterals in 2D, hexahedra in 3D) and `level` (N int32, the leaf's level). Root
//! attributes: time [s], frame. cells_0007.xdmf describes it; cells.xdmf gathers the frames as
//! a time series. Files are replaced atomically (io/atomic_file.h).
#include <mpm/adaptive/cell_tree.h>

#include <filesystem>
#include <utility>
#include <vector>

namespace mpm::io {

template <int dim>
void write_cells(const std::filesystem::path& h5_path, const adaptive::CellTree<dim>& tree, double time, int frame,
                 const std::string& run_id = "");

//! Writes dir/cells.xdmf over the frames (frame, time [s]); each dir/cells_NNNN.h5 must exist.
template <int dim>
void write_cells_time_series(const std::filesystem::path& dir, const std::vector<std::pair<int, double>>& frames);

}  // namespace mpm::io
