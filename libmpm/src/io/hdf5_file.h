#pragma once
//! Internal to the I/O module: a thin RAII layer over the HDF5 C API, shared by the particle
//! output and the checkpoints. Every failure throws IoError naming the file, the object and
//! HDF5's own reason; HDF5's automatic printing of its error stack is off while a file is open.
#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace mpm::io::detail {

//! The HDF5 type in memory and the little-endian type on disk of a C++ value type.
template <class T>
struct Hdf5Type;
template <>
struct Hdf5Type<double> {
  static hid_t memory() { return H5T_NATIVE_DOUBLE; }
  static hid_t file() { return H5T_IEEE_F64LE; }
};
template <>
struct Hdf5Type<std::int32_t> {
  static hid_t memory() { return H5T_NATIVE_INT32; }
  static hid_t file() { return H5T_STD_I32LE; }
};
template <>
struct Hdf5Type<std::int64_t> {
  static hid_t memory() { return H5T_NATIVE_INT64; }
  static hid_t file() { return H5T_STD_I64LE; }
};
template <>
struct Hdf5Type<std::uint16_t> {
  static hid_t memory() { return H5T_NATIVE_UINT16; }
  static hid_t file() { return H5T_STD_U16LE; }
};

using Shape = std::vector<hsize_t>;

class Hdf5File {
public:
  enum class Mode { create, read };

  //! Creates (truncating) or opens `file` read-only; messages name `reported` (an AtomicFile
  //! writes a temporary file but the user knows the target).
  Hdf5File(const std::filesystem::path& file, Mode mode, const std::filesystem::path& reported);
  Hdf5File(const std::filesystem::path& file, Mode mode) : Hdf5File(file, mode, file) {}
  ~Hdf5File();
  Hdf5File(const Hdf5File&) = delete;
  Hdf5File& operator=(const Hdf5File&) = delete;

  //! Writes a dataset of `shape` from contiguous row-major `data`; a path "group/name"
  //! creates the group.
  template <class T>
  void write(const std::string& dataset, const T* data, const Shape& shape) {
    write_raw(dataset, Hdf5Type<T>::file(), Hdf5Type<T>::memory(), data, shape);
  }
  //! Reads a dataset into `data` after checking that it has exactly `shape`.
  template <class T>
  void read(const std::string& dataset, T* data, const Shape& shape) const {
    read_raw(dataset, Hdf5Type<T>::memory(), data, shape);
  }
  bool has(const std::string& dataset) const;
  Shape shape(const std::string& dataset) const;
  //! Whether the dataset stores integers (else floating-point numbers).
  bool holds_integers(const std::string& dataset) const;

  //! Scalar attributes of the root group.
  template <class T>
  void write_attribute(const std::string& name, T value) {
    write_attribute_raw(name, Hdf5Type<T>::file(), Hdf5Type<T>::memory(), &value);
  }
  void write_attribute(const std::string& name, const std::string& value);
  template <class T>
  T read_attribute(const std::string& name) const {
    T value{};
    read_attribute_raw(name, Hdf5Type<T>::memory(), &value);
    return value;
  }
  std::string read_string_attribute(const std::string& name) const;
  bool has_attribute(const std::string& name) const;

  //! Flushes and closes the file, reporting failures (the destructor closes silently).
  void close();

private:
  //! Throws IoError "HDF5 file '<reported>': <what>: <HDF5's innermost reason>".
  [[noreturn]] void fail(const std::string& what) const;
  void write_raw(const std::string& dataset, hid_t file_type, hid_t memory_type, const void* data, const Shape& shape);
  void read_raw(const std::string& dataset, hid_t memory_type, void* data, const Shape& shape) const;
  void write_attribute_raw(const std::string& name, hid_t file_type, hid_t memory_type, const void* value);
  void read_attribute_raw(const std::string& name, hid_t memory_type, void* value) const;

  std::filesystem::path path_, reported_;
  H5E_auto2_t saved_printer_ = nullptr;
  void* saved_printer_data_ = nullptr;
  hid_t file_ = H5I_INVALID_HID;
};

}  // namespace mpm::io::detail
