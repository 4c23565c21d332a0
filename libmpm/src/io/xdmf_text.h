#pragma once
//! Internal to the I/O module: the XDMF 3 document around a run of <Grid> elements.
#include <string>

namespace mpm::io::detail {

inline std::string xdmf_document(const std::string& grids) {
  return "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n  <Domain>\n" +
         grids + "  </Domain>\n</Xdmf>\n";
}

}  // namespace mpm::io::detail
