#include <mpm/io/particle_output.h>

#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>

#include "channel_sizes.h"
#include "hdf5_file.h"
#include "number_text.h"

#include <Eigen/LU>  // determinant()

#include <cstdint>
#include <cstdio>

namespace mpm::io {
namespace {

//! The datasets of a frame besides position, in the order the XDMF lists them.
struct Channel {
  const char* name;
  bool is_vector;          // N x 3, else N
  bool is_integer;         // int32, else double
  bool needs_deformation;  // present only when the particles carry F
};
constexpr Channel kAttributes[] = {
    {"velocity", true, false, false}, {"mass", false, false, false},
    {"volume0", false, false, false}, {"material", false, true, false},
    {"speed", false, false, false},   {"J", false, false, true},
    {"plastic", false, false, true}};

std::string escape_xml(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

//! The Uniform grid of one frame: n particles stored in the HDF5 file `h5_name` (relative to
//! the XDMF file), J and plastic included when `has_deformation`.
std::string frame_grid(const std::string& h5_name, hsize_t n, bool has_deformation, double time,
                       const std::string& indent) {
  const std::string file = escape_xml(h5_name);
  const auto data_item = [&](const char* dataset, bool is_vector, bool is_integer) {
    return indent + "    <DataItem Dimensions=\"" + std::to_string(n) + (is_vector ? " 3" : "") +
           "\" NumberType=\"" + (is_integer ? "Int\" Precision=\"4" : "Float\" Precision=\"8") +
           "\" Format=\"HDF\">" + file + ":/" + dataset + "</DataItem>\n";
  };
  std::string xml = indent + "<Grid Name=\"particles\" GridType=\"Uniform\">\n";
  xml += indent + "  <Time Value=\"" + detail::to_text(time) + "\"/>\n";
  xml += indent + "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" +
         std::to_string(n) + "\" NodesPerElement=\"1\"/>\n";
  xml += indent + "  <Geometry GeometryType=\"XYZ\">\n" + data_item("position", true, false) +
         indent + "  </Geometry>\n";
  for (const Channel& c : kAttributes) {
    if (c.needs_deformation && !has_deformation) continue;
    xml += indent + "  <Attribute Name=\"" + c.name + "\" AttributeType=\"" +
           (c.is_vector ? "Vector" : "Scalar") + "\" Center=\"Node\">\n" +
           data_item(c.name, c.is_vector, c.is_integer) + indent + "  </Attribute>\n";
  }
  return xml + indent + "</Grid>\n";
}

std::string xdmf_document(const std::string& grids) {
  return "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
         "<Xdmf Version=\"3.0\">\n  <Domain>\n" +
         grids + "  </Domain>\n</Xdmf>\n";
}

}  // namespace

std::string particle_file_name(int frame, const std::string& stem) {
  verify<InputError>(frame >= 0, "particle output: frame " + std::to_string(frame) + " < 0");
  char number[16];
  std::snprintf(number, sizeof number, "_%04d.h5", frame);
  return stem + number;
}

template <int dim>
void write_particles(const std::filesystem::path& h5_path, const Particles<dim>& p, double time,
                     int frame) {
  detail::verify_channel_sizes(p, h5_path);
  const auto n = static_cast<Eigen::Index>(p.size());
  using RowsOf3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  // N x 3 in HDF5
  RowsOf3 position = RowsOf3::Zero(n, 3), velocity = RowsOf3::Zero(n, 3);
  Eigen::VectorXd speed(n), J(p.has_deformation() ? n : 0);
  Eigen::VectorX<std::int32_t> material(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    position.row(i).head<dim>() = p.x[i].transpose();
    velocity.row(i).head<dim>() = p.v[i].transpose();
    speed[i] = p.v[i].norm();
    material[i] = p.material[i];
    if (p.has_deformation()) J[i] = p.F[i].determinant();
  }

  AtomicFile out(h5_path);
  {
    using detail::Hdf5File;
    Hdf5File file(out.temp_path(), Hdf5File::Mode::create, h5_path);
    const auto rows = static_cast<hsize_t>(n);
    file.write("position", position.data(), {rows, 3});
    file.write("velocity", velocity.data(), {rows, 3});
    file.write("mass", p.mass.data(), {rows});
    file.write("volume0", p.volume0.data(), {rows});
    file.write("material", material.data(), {rows});
    file.write("speed", speed.data(), {rows});
    if (p.has_deformation()) {
      file.write("J", J.data(), {rows});
      file.write("plastic", p.plastic.data(), {rows});
    }
    file.write_attribute("time", time);
    file.write_attribute<std::int32_t>("frame", frame);
    file.write_attribute<std::int32_t>("dim", dim);
    file.close();
  }
  out.commit();

  const std::string grid =
      frame_grid(h5_path.filename().string(), p.size(), p.has_deformation(), time, "    ");
  write_file_atomically(std::filesystem::path(h5_path).replace_extension(".xdmf"),
                        xdmf_document(grid));
}

void write_time_series_xdmf(const std::filesystem::path& dir,
                            const std::vector<std::pair<int, double>>& frames, const std::string& stem) {
  std::string grids =
      "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& [frame, time] : frames) {
    const std::string name = particle_file_name(frame, stem);
    const detail::Hdf5File file(dir / name, detail::Hdf5File::Mode::read);
    const detail::Shape position = file.shape("position");
    if (position.size() != 2 || position[1] != 3)
      throw IoError("particle file '" + (dir / name).string() +
                    "': dataset 'position' is not N x 3");
    grids += frame_grid(name, position[0], file.has("J"), time, "      ");
  }
  grids += "    </Grid>\n";
  write_file_atomically(dir / (stem + ".xdmf"), xdmf_document(grids));
}

template void write_particles<2>(const std::filesystem::path&, const Particles<2>&, double, int);
template void write_particles<3>(const std::filesystem::path&, const Particles<3>&, double, int);

}  // namespace mpm::io
