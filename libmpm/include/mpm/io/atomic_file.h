#pragma once
//! Atomic replacement of output files.
//!
//! Every output file is written to "<path>.tmp-<pid>" in the same folder and renamed over
//! <path> once complete, so ParaView polling a running simulation, or a run killed mid-write,
//! never sees a half-written file (rename within one file system is atomic on POSIX). The temp
//! file is not fsync'ed: the guarantee covers a crashing or killed process, not a power loss.
#include <cstddef>
#include <filesystem>
#include <string_view>

namespace mpm::io {

//! A temporary sibling of `target` for libraries that write files themselves (HDF5, libpng):
//! write temp_path(), then commit() renames it over target. Destroyed uncommitted (an exception
//! on the way), it removes the temporary file, so a failed write leaves no partial file.
class AtomicFile {
public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::filesystem::path& target() const { return target_; }
  const std::filesystem::path& temp_path() const { return temp_; }

  //! Renames the temporary file over target; throws IoError naming target and the reason.
  void commit();

private:
  std::filesystem::path target_;
  std::filesystem::path temp_;
  bool committed_ = false;
};

//! Writes `content` to `path` (created or truncated) with POSIX I/O, not atomically: for the
//! temporary file of an AtomicFile. Throws IoError naming the path and errno's reason (ENOSPC,
//! EACCES, ...).
void write_whole_file(const std::filesystem::path& path, std::string_view content);

//! Writes `content` to `path` atomically; throws IoError naming the path and the reason.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

//! Removes the temporary files "<name>.tmp-<pid>" in `folder` (not its subfolders) that a killed
//! process left behind: those whose process no longer runs. Files of this process and of live
//! ones stay. Returns the number removed; a missing folder removes nothing.
std::size_t remove_stale_temporaries(const std::filesystem::path& folder);

}  // namespace mpm::io
