#pragma once
//! summary.json: the results of a run next to the parameters that produced them.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace mpm::io {

//! Writes {"results": {...}, "parameters": {...}, "info": {...}}, keys in the given order, and
//! replaces the file atomically (io/atomic_file.h).
//!  - results: numbers, written so that they read back to the same double; a NaN or infinite
//!    result is written as null (JSON has no non-finite numbers).
//!  - parameters: YAML scalar text as resolved from the scene. A value that parses fully as an
//!    integer or a finite double becomes a JSON number, true/True/TRUE and false/False/FALSE
//!    (YAML 1.2 core schema) become booleans, anything else stays a string.
//!  - info: strings (version, host, date, ...).
//! A key repeated within one section throws InputError; a failed write throws IoError.
void write_summary(const std::filesystem::path& path, const std::vector<std::pair<std::string, double>>& results,
                   const std::vector<std::pair<std::string, std::string>>& parameters,
                   const std::vector<std::pair<std::string, std::string>>& info);

}  // namespace mpm::io
