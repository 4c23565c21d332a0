#pragma once
//! Internal to the I/O module: XDMF 3 text shared by the writers.
#include "number_text.h"

#include <cstddef>
#include <string>

namespace mpm::io::detail {

inline std::string xdmf_document(const std::string& grids) {
  return "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n  <Domain>\n" +
         grids + "  </Domain>\n</Xdmf>\n";
}

//! A <Grid> named `name` of an unstructured mesh in the HDF5 file `h5_name`: `elements` rows of
//! `nodes_per_element` int32 indices in dataset `connectivity`, `points` rows of 3 doubles in
//! dataset "points", at `time` [s]; `topology` is the Topology element's type attributes and
//! `inner` further XML (attributes), each line indented by `indent` + two spaces.
inline std::string mesh_grid(const std::string& name, const std::string& topology, std::size_t elements,
                             int nodes_per_element, const std::string& connectivity, std::size_t points,
                             const std::string& h5_name, double time, const std::string& indent,
                             const std::string& inner = "") {
  std::string xml = indent + "<Grid Name=\"" + name + "\" GridType=\"Uniform\">\n";
  xml += indent + "  <Time Value=\"" + to_text(time) + "\"/>\n";
  xml += indent + "  <Topology " + topology + " NumberOfElements=\"" + std::to_string(elements) + "\">\n";
  xml += indent + "    <DataItem Dimensions=\"" + std::to_string(elements) + " " + std::to_string(nodes_per_element) +
         "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" + h5_name + ":/" + connectivity + "</DataItem>\n";
  xml += indent + "  </Topology>\n";
  xml += indent + "  <Geometry GeometryType=\"XYZ\">\n";
  xml += indent + "    <DataItem Dimensions=\"" + std::to_string(points) +
         " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" + h5_name + ":/points</DataItem>\n";
  xml += indent + "  </Geometry>\n";
  return xml + inner + indent + "</Grid>\n";
}

}  // namespace mpm::io::detail
