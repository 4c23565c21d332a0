#pragma once
//! Internal to the I/O module: a per-frame HDF5 file written atomically (io/atomic_file.h).
#include <mpm/io/atomic_file.h>

#include "hdf5_file.h"

#include <cstdint>
#include <filesystem>
#include <string>

namespace mpm::io::detail {

//! Creates h5_path: write(Hdf5File&) adds the datasets, then the attributes time [s], frame and
//! (when given) run_id; the file replaces h5_path only when complete.
template <class Write>
void write_frame_file(const std::filesystem::path& h5_path, double time, int frame, const std::string& run_id,
                      Write&& write) {
  AtomicFile out(h5_path);
  {
    Hdf5File file(out.temp_path(), Hdf5File::Mode::create, h5_path);
    write(file);
    file.write_attribute("time", time);
    file.write_attribute<std::int32_t>("frame", frame);
    if (!run_id.empty()) file.write_attribute("run_id", run_id);
    file.close();
  }
  out.commit();
}

}  // namespace mpm::io::detail
