#include <mpm/io/diagnostics_csv.h>

#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>

#include "number_text.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <iterator>
#include <utility>

namespace mpm::io {
namespace {

std::string header_line(const std::vector<std::string>& columns) {
  std::string line;
  for (std::size_t i = 0; i < columns.size(); ++i) line += (i ? "," : "") + columns[i];
  return line;
}

void verify_columns(const std::vector<std::string>& columns, const std::filesystem::path& path) {
  verify<InputError>(!columns.empty(), "diagnostics '" + path.string() + "': no columns");
  for (const std::string& name : columns)
    verify<InputError>(!name.empty() && name.find_first_of(",\"\r\n") == std::string::npos,
                       "diagnostics '" + path.string() + "': column name '" + name +
                           "' is empty or holds a comma, quote or line break");
}

//! The comma-separated fields of one line.
std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> fields;
  for (std::size_t start = 0;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma - start));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

//! One row as the file holds it: 17 significant digits, so that it reads back to the same doubles.
std::string row_line(const std::vector<double>& row) {
  std::string line;
  for (std::size_t i = 0; i < row.size(); ++i) line += (i ? "," : "") + detail::to_text(row[i]);
  return line + '\n';
}

}  // namespace

void DiagnosticsCsv::open(const std::filesystem::path& path, std::vector<std::string> columns) {
  verify_columns(columns, path);
  path_ = path;
  columns_ = std::move(columns);
  rows_.clear();
  open_file("w");
  const std::string header = header_line(columns_) + "\n";
  if (std::fputs(header.c_str(), file_.get()) < 0 || std::fflush(file_.get()) != 0)
    throw IoError("cannot write '" + path_.string() + "': " + std::strerror(errno));
}

void DiagnosticsCsv::load(const std::filesystem::path& path, std::vector<std::string> columns) {
  verify_columns(columns, path);
  verify<InputError>(std::find(columns.begin(), columns.end(), "frame") != columns.end(),
                     "diagnostics '" + path.string() + "': restart needs a 'frame' column");

  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot reopen '" + path.string() + "' for a restart: " + std::strerror(errno));
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string header = header_line(columns);

  // Only lines ending in '\n' are complete; text after the last one is a row cut short.
  std::vector<std::vector<double>> rows;
  std::size_t line_number = 0;
  for (std::size_t start = 0, end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
    const std::string_view line(text.data() + start, end - start);
    const std::string where = path.string() + ":" + std::to_string(++line_number);
    if (line_number == 1) {
      if (line != header) throw IoError(where + ": header '" + std::string(line) + "' differs from '" + header + "'");
      continue;
    }
    const std::vector<std::string_view> fields = split(line);
    if (fields.size() != columns.size())
      throw IoError(where + ": " + std::to_string(fields.size()) + " fields, the header has " +
                    std::to_string(columns.size()));
    std::vector<double> row(fields.size());
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const auto [end_of_number, error] =
          std::from_chars(fields[c].data(), fields[c].data() + fields[c].size(), row[c]);
      if (error != std::errc() || end_of_number != fields[c].data() + fields[c].size())
        throw IoError(where + ": " + columns[c] + " '" + std::string(fields[c]) + "' is not a number");
    }
    rows.push_back(std::move(row));
  }
  if (line_number == 0) throw IoError("'" + path.string() + "' has no header line");
  file_.reset();
  path_ = path;
  columns_ = std::move(columns);
  rows_ = std::move(rows);
}

void DiagnosticsCsv::keep_until(int last_frame_kept) {
  verify<IoError>(!path_.empty() && !is_open(), "diagnostics: keep_until without load");
  const std::size_t frame = std::find(columns_.begin(), columns_.end(), "frame") - columns_.begin();
  std::erase_if(rows_, [&](const std::vector<double>& row) { return row[frame] > last_frame_kept; });
  std::string text = header_line(columns_) + "\n";
  for (const auto& row : rows_) text += row_line(row);
  write_file_atomically(path_, text);
  open_file("a");
}

void DiagnosticsCsv::append(const std::vector<double>& row) {
  verify<IoError>(is_open(), "diagnostics: append before open");
  if (row.size() != columns_.size())
    throw IoError("cannot append to '" + path_.string() + "': the row has " + std::to_string(row.size()) +
                  " values, the header " + std::to_string(columns_.size()) + " columns");
  const std::string line = row_line(row);
  if (std::fputs(line.c_str(), file_.get()) < 0 || std::fflush(file_.get()) != 0)
    throw IoError("cannot append to '" + path_.string() + "': " + std::strerror(errno));
  rows_.push_back(row);
}

std::vector<double> DiagnosticsCsv::column(const std::string& name) const {
  const auto c = std::find(columns_.begin(), columns_.end(), name) - columns_.begin();
  verify<InputError>(c < std::ssize(columns_), "diagnostics '" + path_.string() + "': no column '" + name + "'");
  std::vector<double> values;
  for (const auto& row : rows_) values.push_back(row[static_cast<std::size_t>(c)]);
  return values;
}

void DiagnosticsCsv::open_file(const char* mode) {
  file_.reset(std::fopen(path_.c_str(), mode));
  if (!file_) throw IoError("cannot open '" + path_.string() + "': " + std::strerror(errno));
}

}  // namespace mpm::io
