#pragma once
//! The entry point shared by every app: parses the command line, runs the scene, and turns
//! errors into one message on stderr and an exit code:
//!   0 success, 1 --check failed, 2 input error (nothing written), 3 numerical error (the
//!   message names stage, particle and quantity), 4 I/O error, 130 / 143 stopped by SIGINT /
//!   SIGTERM after writing a checkpoint to continue from (core/stop_signals.h).
#include <mpm/core/command_line.h>

#include <functional>
#include <string>
#include <vector>

namespace mpm {

int run_app(int argc, char** argv, const std::string& app_name, const std::string& description,
            const std::function<int(const CommandLine&)>& body);

class Config;

//! run_app for a scene file: loads the scene with the --set overrides and calls run_2d or
//! run_3d according to its "dim" key.
using SceneRunner = int (*)(const CommandLine&, const Config&);
int run_scene_app(int argc, char** argv, const std::string& app_name, const std::string& description,
                  SceneRunner run_2d, SceneRunner run_3d);

//! The threads the parallel loops of this process may use: --threads, else every core it may
//! run on (the summary's "threads").
int worker_threads();

//! Prints "check <name>: value (expected ..., tolerance ...) ok|FAILED" and returns whether
//! |value - expected| <= tolerance. A failed check is also recorded: run_app then exits with 1
//! under --check even when the app's own verdict was 0, so checks made outside the app (the
//! Runner's solves_converged) cannot be lost.
bool check_value(const std::string& name, double value, double expected, double tolerance);
//! Whether a check_value (or check_solve_residuals) of this process failed.
bool any_check_failed();

//! The relative residual a linear solve must reach for a --check to trust the run: the loosest
//! pressure tolerance a shipped scene asks for (sediment_transport_3d.yaml; the default is 1e-8,
//! most scenes ask 1e-8 or 1e-10).
inline constexpr double check_max_solve_residual = 1e-6;

//! The second half of the Runner's check of a run's solves under --check (the first: every
//! "<solve>_unconverged" column ends at 0). For a solve that flags its round-off floor (column
//! "<solve>_round_off", the pressure projections), the relative residual of each frame's last
//! solve (column "<solve>_residual") must be at most `max_residual` in every frame not flagged.
//! This catches a tolerance loosened in the scene: pressure.tolerance = 0.5 with
//! max_iterations = 1 "converges" to its own tolerance, and the error of such a run can pass
//! the app's error check. Prints
//!   check <solve>_converged: <largest residual> (expected residual <= <max_residual> ...) ok|FAILED
//! and records a failure as check_value does.
bool check_solve_residuals(const std::string& solve, const std::vector<double>& residual,
                           const std::vector<double>& round_off, double max_residual);

}  // namespace mpm
