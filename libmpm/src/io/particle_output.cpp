#include <mpm/io/particle_output.h>

#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>

#include "channel_sizes.h"
#include "hdf5_file.h"
#include "number_text.h"
#include "xdmf_text.h"

#include <Eigen/LU>  // determinant()

#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace mpm::io {
namespace {

//! The frame dataset of channel x (core/particles.h): the geometry of the XDMF grid; every other
//! dataset of a frame is one of its attributes.
constexpr const char* kGeometry = "position";
//! Root attribute of a frame file: its attribute datasets, one a line, in XDMF order, so that
//! the time series describes frames written by an earlier process (a restart) as they are.
constexpr const char* kAttributeList = "attributes";

//! An attribute of a frame: its dataset and how XDMF describes it.
struct Attribute {
  std::string name;
  bool is_vector;   // N x 3, else N
  bool is_integer;  // int32, else double
};

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
//! the XDMF file), with the datasets `attributes` besides the geometry.
std::string frame_grid(const std::string& h5_name, hsize_t n, const std::vector<Attribute>& attributes, double time,
                       const std::string& indent) {
  const std::string file = escape_xml(h5_name);
  const auto data_item = [&](const std::string& dataset, bool is_vector, bool is_integer) {
    return indent + "    <DataItem Dimensions=\"" + std::to_string(n) + (is_vector ? " 3" : "") + "\" NumberType=\"" +
           (is_integer ? "Int\" Precision=\"4" : "Float\" Precision=\"8") + "\" Format=\"HDF\">" + file + ":/" +
           dataset + "</DataItem>\n";
  };
  std::string xml = indent + "<Grid Name=\"particles\" GridType=\"Uniform\">\n";
  xml += indent + "  <Time Value=\"" + detail::to_text(time) + "\"/>\n";
  xml += indent + "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" + std::to_string(n) +
         "\" NodesPerElement=\"1\"/>\n";
  xml +=
      indent + "  <Geometry GeometryType=\"XYZ\">\n" + data_item(kGeometry, true, false) + indent + "  </Geometry>\n";
  for (const Attribute& c : attributes) {
    xml += indent + "  <Attribute Name=\"" + escape_xml(c.name) + "\" AttributeType=\"" +
           (c.is_vector ? "Vector" : "Scalar") + "\" Center=\"Node\">\n" +
           data_item(c.name, c.is_vector, c.is_integer) + indent + "  </Attribute>\n";
  }
  return xml + indent + "</Grid>\n";
}

//! Writes one channel to a frame as ParaView reads it and returns its description: Vec as N x 3
//! (2D padded with z = 0), a matrix as its determinant (J = det F^E for the deformation
//! gradient), uint16 as int32, double as it is.
template <int dim, class T>
Attribute write_frame_dataset(detail::Hdf5File& file, const std::string& name, const std::vector<T>& values) {
  const auto n = static_cast<Eigen::Index>(values.size());
  const auto rows = static_cast<hsize_t>(n);
  if constexpr (std::is_same_v<T, Vec<dim>>) {
    using RowsOf3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  // N x 3 in HDF5
    RowsOf3 padded = RowsOf3::Zero(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) padded.row(i).template head<dim>() = values[i].transpose();
    file.write(name, padded.data(), {rows, 3});
    return {name, true, false};
  } else if constexpr (std::is_same_v<T, Mat<dim>>) {
    std::vector<double> determinant(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) determinant[i] = values[i].determinant();
    file.write(name, determinant.data(), {rows});
    return {name, false, false};
  } else if constexpr (std::is_same_v<T, std::uint16_t>) {
    const std::vector<std::int32_t> wide(values.begin(), values.end());
    file.write(name, wide.data(), {rows});
    return {name, false, true};
  } else {
    static_assert(std::is_same_v<T, double>);
    file.write(name, values.data(), {rows});
    return {name, false, false};
  }
}

}  // namespace

std::string particle_file_name(int frame, const std::string& stem) {
  verify<InputError>(frame >= 0, "particle output: frame " + std::to_string(frame) + " < 0");
  char number[16];
  std::snprintf(number, sizeof number, "_%04d.h5", frame);
  return stem + number;
}

template <int dim>
void write_particles(const std::filesystem::path& h5_path, const Particles<dim>& p, double time, int frame,
                     const std::string& run_id) {
  detail::verify_channel_sizes(p, h5_path);
  const auto rows = static_cast<hsize_t>(p.size());
  std::vector<Attribute> attributes;
  AtomicFile out(h5_path);
  {
    using detail::Hdf5File;
    Hdf5File file(out.temp_path(), Hdf5File::Mode::create, h5_path);
    p.for_each_channel([&](const ChannelInfo& info, const auto& values) {
      if (!info.use.output) return;
      const Attribute written = write_frame_dataset<dim>(file, info.frame_name(), values);
      if (written.name != kGeometry) attributes.push_back(written);
    });
    // |v|, derived rather than stored: the quantity most often coloured by.
    std::vector<double> speed(p.size());
    for (std::size_t i = 0; i < speed.size(); ++i) speed[i] = p.v[i].norm();
    file.write("speed", speed.data(), {rows});
    attributes.push_back({"speed", false, false});
    std::string names;
    for (const Attribute& a : attributes) names += (names.empty() ? "" : "\n") + a.name;
    file.write_attribute(kAttributeList, names);
    file.write_attribute("time", time);
    file.write_attribute<std::int32_t>("frame", frame);
    if (!run_id.empty()) file.write_attribute("run_id", run_id);
    file.write_attribute<std::int32_t>("dim", dim);
    file.close();
  }
  out.commit();

  const std::string grid = frame_grid(h5_path.filename().string(), p.size(), attributes, time, "    ");
  write_file_atomically(std::filesystem::path(h5_path).replace_extension(".xdmf"), detail::xdmf_document(grid));
}

void write_time_series_xdmf(const std::filesystem::path& dir, const std::vector<std::pair<int, double>>& frames,
                            const std::string& stem) {
  std::string grids = "    <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& [frame, time] : frames) {
    const std::string name = particle_file_name(frame, stem);
    const std::string path = (dir / name).string();
    const detail::Hdf5File file(dir / name, detail::Hdf5File::Mode::read);
    const detail::Shape position = file.shape(kGeometry);
    if (position.size() != 2 || position[1] != 3)
      throw IoError("particle file '" + path + "': dataset '" + kGeometry + "' is not N x 3");
    if (!file.has_attribute(kAttributeList))
      throw IoError("particle file '" + path + "' has no attribute '" + kAttributeList + "' listing its datasets");
    std::vector<Attribute> attributes;
    std::stringstream names(file.read_string_attribute(kAttributeList));
    for (std::string dataset; std::getline(names, dataset);) {
      const detail::Shape shape = file.shape(dataset);
      const bool is_vector = shape.size() == 2 && shape[1] == 3;
      if ((shape.size() != 1 && !is_vector) || shape[0] != position[0])
        throw IoError("particle file '" + path + "': dataset '" + dataset + "' is neither N nor N x 3");
      attributes.push_back({dataset, is_vector, file.holds_integers(dataset)});
    }
    grids += frame_grid(name, position[0], attributes, time, "      ");
  }
  grids += "    </Grid>\n";
  write_file_atomically(dir / (stem + ".xdmf"), detail::xdmf_document(grids));
}

template void write_particles<2>(const std::filesystem::path&, const Particles<2>&, double, int, const std::string&);
template void write_particles<3>(const std::filesystem::path&, const Particles<3>&, double, int, const std::string&);

}  // namespace mpm::io
