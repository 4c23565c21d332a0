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

template <int dim>
std::string surface_grid(const std::string& h5_name, std::size_t points, std::size_t faces, double time,
                         const std::string& indent) {
  return detail::mesh_grid(
      "surface", dim == 2 ? "TopologyType=\"Polyline\" NodesPerElement=\"2\"" : "TopologyType=\"Quadrilateral\"", faces,
      1 << (dim - 1), "faces", points, h5_name, time, indent);
}

}  // namespace

template <int dim>
void write_surface(const std::filesystem::path& h5_path, const domains::ParticleDomains<dim>& d, double time, int frame,
                   const std::string& run_id) {
  constexpr int per_face = 1 << (dim - 1);
  std::vector<double> points;
  points.reserve(d.corner_count() * 3);
  for (const Vec<dim>& x : d.x)
    for (int a = 0; a < 3; ++a) points.push_back(a < dim ? x[a] : 0.0);
  std::vector<std::int32_t> faces;
  faces.reserve(d.surface.size() * per_face);
  for (const auto& face : d.surface)
    for (const std::uint32_t c : face) faces.push_back(static_cast<std::int32_t>(c));
  detail::write_frame_file(h5_path, time, frame, run_id, [&](detail::Hdf5File& file) {
    file.write("points", points.data(), {static_cast<hsize_t>(d.corner_count()), 3});
    file.write("faces", faces.data(), {static_cast<hsize_t>(d.surface.size()), static_cast<hsize_t>(per_face)});
  });
  write_file_atomically(std::filesystem::path(h5_path).replace_extension(".xdmf"),
                        detail::xdmf_document(surface_grid<dim>(h5_path.filename().string(), d.corner_count(),
                                                                d.surface.size(), time, "    ")));
}

template <int dim>
void write_surface_time_series(const std::filesystem::path& dir, const std::vector<std::pair<int, double>>& frames) {
  std::string grids = "    <Grid Name=\"surface\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& [frame, time] : frames) {
    const std::string name = particle_file_name(frame, "surface");
    const detail::Hdf5File file(dir / name, detail::Hdf5File::Mode::read);
    grids += surface_grid<dim>(name, static_cast<std::size_t>(file.shape("points").at(0)),
                               static_cast<std::size_t>(file.shape("faces").at(0)), time, "      ");
  }
  write_file_atomically(dir / "surface.xdmf", detail::xdmf_document(grids + "    </Grid>\n"));
}

template void write_surface(const std::filesystem::path&, const domains::ParticleDomains<2>&, double, int,
                            const std::string&);
template void write_surface(const std::filesystem::path&, const domains::ParticleDomains<3>&, double, int,
                            const std::string&);
template void write_surface_time_series<2>(const std::filesystem::path&, const std::vector<std::pair<int, double>>&);
template void write_surface_time_series<3>(const std::filesystem::path&, const std::vector<std::pair<int, double>>&);

}  // namespace mpm::io
