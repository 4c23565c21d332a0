#include <mpm/io/atomic_file.h>
#include <mpm/io/particle_output.h>
#include <mpm/io/surface_output.h>

#include "frame_file.h"
#include "hdf5_file.h"
#include "xdmf_text.h"

#include <cstdint>
#include <string>

namespace mpm::io {
namespace {

//! The two meshes written per frame: the domains' boundary and the embedded mesh.
struct MeshKind {
  std::string stem;          //!< file stem: surface_NNNN.h5, mesh_NNNN.h5
  std::string connectivity;  //!< dataset of the element corners
  std::string topology;      //!< XDMF topology attributes
  int nodes_per_element;
};

template <int dim>
MeshKind boundary_kind() {
  return {"surface", "faces",
          dim == 2 ? "TopologyType=\"Polyline\" NodesPerElement=\"2\"" : "TopologyType=\"Quadrilateral\"",
          1 << (dim - 1)};
}

const MeshKind kEmbedded{"mesh", "triangles", "TopologyType=\"Triangle\"", 3};

std::string mesh_grid(const MeshKind& kind, const std::string& h5_name, std::size_t points, std::size_t elements,
                      double time, const std::string& indent) {
  return detail::mesh_grid(kind.stem, kind.topology, elements, kind.nodes_per_element, kind.connectivity, points,
                           h5_name, time, indent);
}

//! `points` (N x 3, 2D padded with z = 0) and the element corners (M x nodes_per_element int32)
//! into h5_path, with its .xdmf beside it.
template <int dim, std::size_t K>
void write_mesh(const std::filesystem::path& h5_path, const MeshKind& kind, const std::vector<Vec<dim>>& x,
                const std::vector<std::array<std::uint32_t, K>>& elements, double time, int frame,
                const std::string& run_id) {
  std::vector<double> points;
  points.reserve(x.size() * 3);
  for (const Vec<dim>& p : x)
    for (int a = 0; a < 3; ++a) points.push_back(a < dim ? p[a] : 0.0);
  std::vector<std::int32_t> corners;
  corners.reserve(elements.size() * K);
  for (const auto& element : elements)
    for (const std::uint32_t c : element) corners.push_back(static_cast<std::int32_t>(c));
  detail::write_frame_file(h5_path, time, frame, run_id, [&](detail::Hdf5File& file) {
    file.write("points", points.data(), {static_cast<hsize_t>(x.size()), 3});
    file.write(kind.connectivity, corners.data(), {static_cast<hsize_t>(elements.size()), static_cast<hsize_t>(K)});
  });
  write_file_atomically(
      std::filesystem::path(h5_path).replace_extension(".xdmf"),
      detail::xdmf_document(mesh_grid(kind, h5_path.filename().string(), x.size(), elements.size(), time, "    ")));
}

void write_mesh_time_series(const std::filesystem::path& dir, const MeshKind& kind,
                            const std::vector<std::pair<int, double>>& frames) {
  std::string grids = "    <Grid Name=\"" + kind.stem + "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& [frame, time] : frames) {
    const std::string name = particle_file_name(frame, kind.stem);
    const detail::Hdf5File file(dir / name, detail::Hdf5File::Mode::read);
    grids += mesh_grid(kind, name, static_cast<std::size_t>(file.shape("points").at(0)),
                       static_cast<std::size_t>(file.shape(kind.connectivity).at(0)), time, "      ");
  }
  write_file_atomically(dir / (kind.stem + ".xdmf"), detail::xdmf_document(grids + "    </Grid>\n"));
}

}  // namespace

template <int dim>
void write_surface(const std::filesystem::path& h5_path, const domains::ParticleDomains<dim>& d, double time, int frame,
                   const std::string& run_id) {
  write_mesh<dim>(h5_path, boundary_kind<dim>(), d.x, d.surface, time, frame, run_id);
}

template <int dim>
void write_surface_time_series(const std::filesystem::path& dir, const std::vector<std::pair<int, double>>& frames) {
  write_mesh_time_series(dir, boundary_kind<dim>(), frames);
}

template <int dim>
void write_embedded_mesh(const std::filesystem::path& h5_path, const domains::ParticleDomains<dim>& d, double time,
                         int frame, const std::string& run_id) {
  std::vector<Vec<dim>> x(d.embedded_domain.size());
  for (std::size_t v = 0; v < x.size(); ++v) x[v] = d.embedded_position(v);
  write_mesh<dim>(h5_path, kEmbedded, x, d.embedded_triangles, time, frame, run_id);
}

void write_embedded_mesh_time_series(const std::filesystem::path& dir,
                                     const std::vector<std::pair<int, double>>& frames) {
  write_mesh_time_series(dir, kEmbedded, frames);
}

#define MPM_SURFACE_OUTPUT(dim)                                                                                      \
  template void write_surface(const std::filesystem::path&, const domains::ParticleDomains<dim>&, double, int,       \
                              const std::string&);                                                                   \
  template void write_surface_time_series<dim>(const std::filesystem::path&,                                         \
                                               const std::vector<std::pair<int, double>>&);                          \
  template void write_embedded_mesh(const std::filesystem::path&, const domains::ParticleDomains<dim>&, double, int, \
                                    const std::string&);
MPM_SURFACE_OUTPUT(2)
MPM_SURFACE_OUTPUT(3)

}  // namespace mpm::io
