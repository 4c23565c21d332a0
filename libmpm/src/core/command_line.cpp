#include <mpm/core/command_line.h>

#include <tbb/info.h>
#include <CLI/CLI.hpp>

#include <cstdlib>
#include <iostream>

namespace mpm {

int available_cores() { return tbb::info::default_concurrency(); }

CommandLine parse_command_line(int argc, char** argv, const std::string& app_name, const std::string& description) {
  CommandLine cl;
  cl.out_dir = "out/" + app_name;
  std::string restart;

  CLI::App app(description, app_name);
  app.add_option("scene", cl.scene_file, "Scene file (YAML)")->required()->check(CLI::ExistingFile);
  app.add_option("--set", cl.overrides,
                 "Override a scene key, e.g. --set time.end=2 or --set materials.0.density=1000 (repeatable)")
      ->type_name("KEY.PATH=VALUE")
      ->allow_extra_args(false);
  app.add_option("--out", cl.out_dir, "Output directory")->capture_default_str();
  app.add_flag("--check", cl.check, "Compare the result against the reference; exit 1 on failure");
  app.add_option("--restart", restart, "Continue from this checkpoint")->check(CLI::ExistingFile);
  app.add_flag("--quiet", cl.quiet, "No progress line");
  double max_memory = 0.0;
  app.add_option("--max-memory", max_memory,
                 "Refuse a scene whose estimated memory exceeds this many GB (default: the memory available)")
      ->check(CLI::PositiveNumber);
  const int cores = available_cores();
  int threads = 0;
  app.add_option("--threads", threads,
                 "Threads for the run's parallel loops (default: every core this process may use)")
      ->check(CLI::Range(1, cores, "thread count in [1, cores this process may use = " + std::to_string(cores) + "]"));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) std::exit(app.exit(e));
    std::cerr << app_name << ": " << e.what() << "\n\n" << app.help();
    std::exit(2);
  }
  if (!restart.empty()) cl.restart = restart;
  if (max_memory > 0.0) cl.max_memory_gb = max_memory;
  if (threads > 0) cl.threads = threads;
  return cl;
}

}  // namespace mpm
