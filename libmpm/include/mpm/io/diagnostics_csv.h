#pragma once
//! Per-frame diagnostics (energies, momentum, mass, ...) as a CSV table: a header line, then
//! one row per frame, every value with 17 significant digits so that it reads back to the same
//! double.
//!
//! This is the one output file that is not replaced atomically: it grows during the run, and
//! rewriting it whole each frame would cost O(frames^2). Instead every row is flushed as it is
//! appended, so a crashed run keeps all its complete rows; a row cut short by the crash is
//! ignored by load.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace mpm::io {

class DiagnosticsCsv {
public:
  //! Creates (or truncates) the file and writes the header. Column names must be non-empty
  //! and free of commas, quotes and line breaks (InputError otherwise).
  void open(const std::filesystem::path& path, std::vector<std::string> columns);

  //! Reads the file of an earlier run without changing it: every complete row (a row cut short
  //! by a crash is ignored). `columns` must contain "frame" and equal the file's header (IoError
  //! otherwise). column() then reads its values; keep_until() continues it.
  void load(const std::filesystem::path& path, std::vector<std::string> columns);
  //! After load(): rewrites the file (atomically) with the rows whose "frame" is <= last_frame_kept
  //! and reopens it for appending, so a restart from that frame's checkpoint writes the later
  //! rows again.
  void keep_until(int last_frame_kept);

  //! Appends one row and flushes it; throws IoError when the row's length differs from the
  //! header or the write fails.
  void append(const std::vector<double>& row);

  bool is_open() const { return file_ != nullptr; }
  const std::vector<std::string>& columns() const { return columns_; }
  //! Every value of column `name` in the file, one per row (rows kept at a restart included),
  //! so results accumulated over a run survive a restart.
  std::vector<double> column(const std::string& name) const;

private:
  struct Close {
    void operator()(std::FILE* file) const { std::fclose(file); }
  };
  void open_file(const char* mode);

  std::filesystem::path path_;
  std::vector<std::string> columns_;
  std::vector<std::vector<double>> rows_;
  std::unique_ptr<std::FILE, Close> file_;
};

}  // namespace mpm::io
