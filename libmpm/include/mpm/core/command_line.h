#pragma once
//! The command-line contract shared by every app:
//!   APP scene.yaml [--set key.path=value]... [--out DIR] [--check] [--restart CHECKPOINT]
//!       [--quiet] [--max-memory GB] [--threads N]
#include <optional>
#include <string>
#include <vector>

namespace mpm {

struct CommandLine {
  std::string scene_file;
  std::vector<std::string> overrides;   //!< "key.path=value", in order
  std::string out_dir;                  //!< default: "out/<app name>"
  bool check = false;                   //!< compare the result against the app's reference; exit 1 on failure
  std::optional<std::string> restart;   //!< checkpoint to continue from
  bool quiet = false;                   //!< no progress line
  std::optional<double> max_memory_gb;  //!< cap on the memory a scene may claim (core/memory_budget.h)
  //! Threads the run's parallel loops may use, in [1, the cores this process may run on];
  //! default: all of them.
  std::optional<int> threads;
};

//! The cores this process may run on (its CPU mask), the largest --threads accepted.
int available_cores();

//! Parses argv. On --help prints usage and exits 0; on a malformed command line prints the
//! error with usage to stderr and exits 2.
CommandLine parse_command_line(int argc, char** argv, const std::string& app_name, const std::string& description);

}  // namespace mpm
