#pragma once
//! The entry point shared by every app: parses the command line, runs the scene, and turns
//! errors into one message on stderr and an exit code:
//!   0 success, 1 --check failed, 2 input error (nothing written), 3 numerical error (the
//!   message names stage, particle and quantity), 4 I/O error, 130 / 143 stopped by SIGINT /
//!   SIGTERM after writing a checkpoint to continue from (core/stop_signals.h).
#include <mpm/core/command_line.h>

#include <functional>
#include <string>

namespace mpm {

int run_app(int argc, char** argv, const std::string& app_name, const std::string& description,
            const std::function<int(const CommandLine&)>& body);

class Config;

//! run_app for a scene file: loads the scene with the --set overrides and calls run_2d or
//! run_3d according to its "dim" key.
using SceneRunner = int (*)(const CommandLine&, const Config&);
int run_scene_app(int argc, char** argv, const std::string& app_name, const std::string& description,
                  SceneRunner run_2d, SceneRunner run_3d);

//! Prints "check <name>: value (expected ..., tolerance ...) ok|FAILED" and returns whether
//! |value - expected| <= tolerance. A failed check is also recorded: run_app then exits with 1
//! under --check even when the app's own verdict was 0, so checks made outside the app (the
//! Runner's solves_converged) cannot be lost.
bool check_value(const std::string& name, double value, double expected, double tolerance);
//! Whether a check_value of this process failed.
bool any_check_failed();

}  // namespace mpm
