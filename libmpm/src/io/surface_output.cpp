#include <mpm/io/atomic_file.h>
#include <mpm/io/particle_output.h>
#include <mpm/io/surface_output.h>

#include "hdf5_file.h"
#include "number_text.h"
#include "xdmf_text.h"

#include <cstdint>
#include <string>

namespace mpm::io {
namespace {

template <int dim>
std::string surface_grid(const std::string& h5_name, std::size_t points, std::size_t faces, double time,
                         const std::string& indent) {
  constexpr int per_face = 1 << (dim - 1);
  const std::string topology =
      dim == 2 ? "TopologyType=\"Polyline\" NodesPerElement=\"2\"" : "TopologyType=\"Quadrilateral\"";
  std::string xml = indent + "<Grid Name=\"surface\" GridType=\"Uniform\">\n";
  xml += indent + "  <Time Value=\"" + detail::to_text(time) + "\"/>\n";
  xml += indent + "  <Topology " + topology + " NumberOfElements=\"" + std::to_string(faces) + "\">\n";
  xml += indent + "    <DataItem Dimensions=\"" + std::to_string(faces) + " " + std::to_string(per_face) +
         "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" + h5_name + ":/faces</DataItem>\n";
  xml += indent + "  </Topology>\n";
  xml += indent + "  <Geometry GeometryType=\"XYZ\">\n";
  xml += indent + "    <DataItem Dimensions=\"" + std::to_string(points) +
         " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" + h5_name + ":/points</DataItem>\n";
  xml += indent + "  </Geometry>\n";
  return xml + indent + "</Grid>\n";
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
  AtomicFile out(h5_path);
  {
    detail::Hdf5File file(out.temp_path(), detail::Hdf5File::Mode::create, h5_path);
    file.write("points", points.data(), {static_cast<hsize_t>(d.corner_count()), 3});
    file.write("faces", faces.data(), {static_cast<hsize_t>(d.surface.size()), static_cast<hsize_t>(per_face)});
    file.write_attribute("time", time);
    file.write_attribute<std::int32_t>("frame", frame);
    if (!run_id.empty()) file.write_attribute("run_id", run_id);
    file.close();
  }
  out.commit();
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
