#pragma once
// Reading HDF5 files back in tests through the C API, independently of the library's own
// reader (src/io/hdf5_file.h): shapes, datasets and attributes as stored.
#include <doctest/doctest.h>
#include <hdf5.h>

#include <string>
#include <vector>

inline std::vector<hsize_t> dataset_shape(hid_t file, const std::string& name) {
  const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  REQUIRE(set >= 0);
  const hid_t space = H5Dget_space(set);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  H5Sclose(space);
  H5Dclose(set);
  return dims;
}

template <class T>
std::vector<T> read_dataset(hid_t file, const std::string& name, hid_t type) {
  std::size_t count = 1;
  for (const hsize_t d : dataset_shape(file, name)) count *= d;
  std::vector<T> values(count);
  const hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  REQUIRE(H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) >= 0);
  H5Dclose(set);
  return values;
}

template <class T>
T read_attribute(hid_t file, const std::string& name, hid_t type) {
  T value{};
  const hid_t attribute = H5Aopen(file, name.c_str(), H5P_DEFAULT);
  REQUIRE(attribute >= 0);
  REQUIRE(H5Aread(attribute, type, &value) >= 0);
  H5Aclose(attribute);
  return value;
}
