#include <mpm/io/atomic_file.h>
#include <mpm/io/cell_output.h>
#include <mpm/io/particle_output.h>

#include "frame_file.h"
#include "hdf5_file.h"
#include "xdmf_text.h"

#include <cstdint>
#include <string>

namespace mpm::io {
namespace {

// VTK corner order: counter-clockwise in the xy plane, then the same one level up in z.
constexpr int kCorner2[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

template <int dim>
IVec<dim> vtk_corner(int c) {
  IVec<dim> offset;
  offset[0] = kCorner2[c % 4][0];
  offset[1] = kCorner2[c % 4][1];
  if constexpr (dim == 3) offset[2] = c / 4;
  return offset;
}

template <int dim>
std::string cell_grid(const std::string& h5_name, std::size_t n, double time, const std::string& indent) {
  constexpr int corners = 1 << dim;
  const std::string level = indent + "  <Attribute Name=\"level\" AttributeType=\"Scalar\" Center=\"Cell\">\n" +
                            indent + "    <DataItem Dimensions=\"" + std::to_string(n) +
                            "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" + h5_name + ":/level</DataItem>\n" +
                            indent + "  </Attribute>\n";
  return detail::mesh_grid("cells", dim == 2 ? "TopologyType=\"Quadrilateral\"" : "TopologyType=\"Hexahedron\"", n,
                           corners, "cells", n * corners, h5_name, time, indent, level);
}

}  // namespace

template <int dim>
void write_cells(const std::filesystem::path& h5_path, const adaptive::CellTree<dim>& tree, double time, int frame,
                 const std::string& run_id) {
  constexpr int corners = 1 << dim;
  std::vector<double> points;
  std::vector<std::int32_t> cells, level;
  tree.for_each_leaf([&](int n, const IVec<dim>& cell) {
    for (int c = 0; c < corners; ++c) {
      const Vec<dim> x = tree.origin() + tree.dx(n) * (cell + vtk_corner<dim>(c)).template cast<double>();
      for (int a = 0; a < 3; ++a) points.push_back(a < dim ? x[a] : 0.0);
      cells.push_back(static_cast<std::int32_t>(cells.size()));
    }
    level.push_back(n);
  });
  const auto n = static_cast<hsize_t>(level.size());
  detail::write_frame_file(h5_path, time, frame, run_id, [&](detail::Hdf5File& file) {
    file.write("points", points.data(), {n * corners, 3});
    file.write("cells", cells.data(), {n, static_cast<hsize_t>(corners)});
    file.write("level", level.data(), {n});
  });
  write_file_atomically(std::filesystem::path(h5_path).replace_extension(".xdmf"),
                        detail::xdmf_document(cell_grid<dim>(h5_path.filename().string(), level.size(), time, "    ")));
}

template <int dim>
void write_cells_time_series(const std::filesystem::path& dir, const std::vector<std::pair<int, double>>& frames) {
  std::string grids = "    <Grid Name=\"cells\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& [frame, time] : frames) {
    const std::string name = particle_file_name(frame, "cells");
    const detail::Hdf5File file(dir / name, detail::Hdf5File::Mode::read);
    grids += cell_grid<dim>(name, static_cast<std::size_t>(file.shape("level").at(0)), time, "      ");
  }
  write_file_atomically(dir / "cells.xdmf", detail::xdmf_document(grids + "    </Grid>\n"));
}

template void write_cells(const std::filesystem::path&, const adaptive::CellTree<2>&, double, int, const std::string&);
template void write_cells(const std::filesystem::path&, const adaptive::CellTree<3>&, double, int, const std::string&);
template void write_cells_time_series<2>(const std::filesystem::path&, const std::vector<std::pair<int, double>>&);
template void write_cells_time_series<3>(const std::filesystem::path&, const std::vector<std::pair<int, double>>&);

}  // namespace mpm::io
