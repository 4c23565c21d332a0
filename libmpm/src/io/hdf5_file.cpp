#include "hdf5_file.h"

#include <mpm/core/error.h>
#include <mpm/core/huge_pages.h>
#include <mpm/io/atomic_file.h>

#include <algorithm>
#include <memory>
#include <new>

namespace mpm::io::detail {
namespace {

//! Closes an HDF5 identifier when it goes out of scope.
class Handle {
public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  bool valid() const { return id_ >= 0; }
  operator hid_t() const { return id_; }

private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

//! The innermost entry of HDF5's error stack, the most specific ("file signature not found",
//! "No such file or directory"); clears the stack.
std::string take_reason() {
  std::string reason = "unknown reason";
  const auto innermost = [](unsigned n, const H5E_error2_t* error, void* out) -> herr_t {
    if (n == 0 && error->desc) *static_cast<std::string*>(out) = error->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost, &reason);
  H5Eclear2(H5E_DEFAULT);
  return reason;
}

//! Room for a file image of `size` bytes, not zero-filled (the image is copied over all of
//! it) and advised for huge pages: a checkpoint's image is hundreds of MB, and its first touch
//! page by page cost more than the copy (huge_pages.h).
std::unique_ptr<char[]> image_buffer(std::size_t size) {
  std::unique_ptr<char[]> image(new (std::nothrow) char[size]);
  advise_huge_pages(image.get(), size);
  return image;
}

std::string describe(const Shape& shape) {
  std::string text = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) text += (i ? ", " : "") + std::to_string(shape[i]);
  return text + "]";
}

}  // namespace

Hdf5File::Hdf5File(const std::filesystem::path& file, Mode mode, const std::filesystem::path& reported)
    : path_(file), reported_(reported) {
  H5Eget_auto2(H5E_DEFAULT, &saved_printer_, &saved_printer_data_);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (mode == Mode::create) {
    // A new file is built in memory (the core driver without a backing store) and written out by
    // close() in one POSIX write: HDF5 itself never writes to disk, so a full disk is an error
    // with errno's reason instead of a file HDF5 cannot close (it crashed at exit retrying).
    const Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    if (access.valid() && H5Pset_fapl_core(access, 1 << 20, false) >= 0)
      file_ = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access);
  } else {
    file_ = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  }
  if (file_ < 0) {
    // The destructor does not run for a throwing constructor: restore the printer here.
    const std::string reason = take_reason();
    H5Eset_auto2(H5E_DEFAULT, saved_printer_, saved_printer_data_);
    throw IoError("HDF5 file '" + reported_.string() + "': cannot " + (mode == Mode::create ? "create" : "open") +
                  " it: " + reason);
  }
}

Hdf5File::~Hdf5File() {
  if (file_ >= 0) H5Fclose(file_);
  H5Eclear2(H5E_DEFAULT);
  H5Eset_auto2(H5E_DEFAULT, saved_printer_, saved_printer_data_);
}

void Hdf5File::close() {
  const hid_t file = file_;
  file_ = H5I_INVALID_HID;
  std::unique_ptr<char[]> image;
  std::size_t size = 0;
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) >= 0) {
    const ssize_t bytes = H5Fget_file_image(file, nullptr, 0);
    if (bytes > 0) {
      size = static_cast<std::size_t>(bytes);
      image = image_buffer(size);
      if (!image) {
        H5Fclose(file);
        throw IoError("HDF5 file '" + reported_.string() + "': no memory for its image of " + std::to_string(size) +
                      " bytes");
      }
      if (H5Fget_file_image(file, image.get(), size) != bytes) image.reset();
    }
  }
  if (H5Fclose(file) < 0 || !image) fail("cannot flush and close it");
  try {
    write_whole_file(path_, std::string_view(image.get(), size));
  } catch (const IoError& e) {
    throw IoError("HDF5 file '" + reported_.string() + "': " + e.what());
  }
}

void Hdf5File::fail(const std::string& what) const {
  throw IoError("HDF5 file '" + reported_.string() + "': " + what + ": " + take_reason());
}

void Hdf5File::write_raw(const std::string& dataset, hid_t file_type, hid_t memory_type, const void* data,
                         const Shape& shape) {
  const Handle space(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr), H5Sclose);
  if (!space.valid()) fail("cannot describe dataset '" + dataset + "' of shape " + describe(shape));
  // "fluid/x" creates the group "fluid" on the way (checkpoints of several phases).
  const Handle links(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  if (!links.valid() || H5Pset_create_intermediate_group(links, 1) < 0)
    fail("cannot set up the creation of dataset '" + dataset + "'");
  const Handle set(H5Dcreate2(file_, dataset.c_str(), file_type, space, links, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  if (!set.valid()) fail("cannot create dataset '" + dataset + "'");
  const bool empty = std::find(shape.begin(), shape.end(), hsize_t{0}) != shape.end();
  if (!empty && H5Dwrite(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    fail("cannot write dataset '" + dataset + "'");
}

bool Hdf5File::has(const std::string& dataset) const { return H5Lexists(file_, dataset.c_str(), H5P_DEFAULT) > 0; }

Shape Hdf5File::shape(const std::string& dataset) const {
  const Handle set(H5Dopen2(file_, dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid()) fail("cannot open dataset '" + dataset + "'");
  const Handle space(H5Dget_space(set), H5Sclose);
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space) : -1;
  if (rank < 0) fail("cannot read the shape of dataset '" + dataset + "'");
  Shape dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  return dims;
}

bool Hdf5File::holds_integers(const std::string& dataset) const {
  const Handle set(H5Dopen2(file_, dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid()) fail("cannot open dataset '" + dataset + "'");
  const Handle type(H5Dget_type(set), H5Tclose);
  if (!type.valid()) fail("cannot read the type of dataset '" + dataset + "'");
  return H5Tget_class(type) == H5T_INTEGER;
}

void Hdf5File::read_raw(const std::string& dataset, hid_t memory_type, void* data, const Shape& expected) const {
  const Shape stored = shape(dataset);
  if (stored != expected)
    throw IoError("HDF5 file '" + reported_.string() + "': dataset '" + dataset + "' has shape " + describe(stored) +
                  ", expected " + describe(expected));
  if (std::find(stored.begin(), stored.end(), hsize_t{0}) != stored.end()) return;
  const Handle set(H5Dopen2(file_, dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.valid() || H5Dread(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
    fail("cannot read dataset '" + dataset + "'");
}

void Hdf5File::write_attribute_raw(const std::string& name, hid_t file_type, hid_t memory_type, const void* value) {
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  const Handle attribute(H5Acreate2(file_, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attribute.valid() || H5Awrite(attribute, memory_type, value) < 0) fail("cannot write attribute '" + name + "'");
}

void Hdf5File::write_attribute(const std::string& name, const std::string& value) {
  // Fixed-length, NUL-padded: the simplest string type every HDF5 reader understands. HDF5
  // has no zero-length fixed strings, so "" is stored as one NUL.
  const Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type, std::max<std::size_t>(value.size(), 1));
  H5Tset_strpad(type, H5T_STR_NULLPAD);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  write_attribute_raw(name, type, type, padded.data());
}

void Hdf5File::read_attribute_raw(const std::string& name, hid_t memory_type, void* value) const {
  const Handle attribute(H5Aopen(file_, name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!attribute.valid()) fail("cannot open attribute '" + name + "'");
  const Handle space(H5Aget_space(attribute), H5Sclose);
  if (H5Sget_simple_extent_npoints(space) != 1)
    throw IoError("HDF5 file '" + reported_.string() + "': attribute '" + name + "' is not a scalar");
  if (H5Aread(attribute, memory_type, value) < 0) fail("cannot read attribute '" + name + "'");
}

bool Hdf5File::has_attribute(const std::string& name) const { return H5Aexists(file_, name.c_str()) > 0; }

std::string Hdf5File::read_string_attribute(const std::string& name) const {
  const Handle attribute(H5Aopen(file_, name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!attribute.valid()) fail("cannot open attribute '" + name + "'");
  const Handle type(H5Aget_type(attribute), H5Tclose);
  if (H5Tget_class(type) != H5T_STRING || H5Tis_variable_str(type) != 0)
    throw IoError("HDF5 file '" + reported_.string() + "': attribute '" + name + "' is not a fixed-length string");
  std::string value(H5Tget_size(type), '\0');
  if (H5Aread(attribute, type, value.data()) < 0) fail("cannot read attribute '" + name + "'");
  value.erase(std::find(value.begin(), value.end(), '\0'), value.end());
  return value;
}

}  // namespace mpm::io::detail
