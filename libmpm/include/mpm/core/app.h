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

//! Prints "check <name>: value (expected ..., tolerance ...) ok|FAILED" and returns whether
//! |value - expected| <= tolerance. A failed check is also recorded: run_app then exits with 1
//! under --check even when the app's own verdict was 0, so checks made outside the app (the
//! Runner's solves_converged) cannot be lost.
bool check_value(const std::string& name, double value, double expected, double tolerance);
//! Whether a check_value (or check_solves_converged) of this process failed.
bool any_check_failed();

//! The check every app's --check makes on its solves, from the run's per-frame diagnostics:
//! `unconverged` (column "<solve>_unconverged": the solves over every step, a restart included,
//! that missed their tolerance and went on, on_failure: warn) must end at 0, and `residual`
//! (column "<solve>_residual": the relative residual of each frame's last solve) must be at most
//! `max_residual` in every frame that `round_off` (column "<solve>_round_off") does not flag as
//! stopped at its round-off floor. The second part catches a tolerance loosened in the scene:
//! pressure.tolerance = 0.5 with max_iterations = 1 "converges" to its own tolerance, and the
//! error of such a run can pass the app's error check. Prints
//!   check <solve>_converged: <largest residual> (expected 0 unconverged and residual <=
//!   <max_residual>; <n> unconverged solves) ok|FAILED
//! and records a failure as check_value does. Columns that no stage reports are empty or zero
//! (Runner::history_or_zero) and pass.
bool check_solves_converged(const std::string& solve, const std::vector<double>& unconverged,
                            const std::vector<double>& residual, const std::vector<double>& round_off,
                            double max_residual);

//! The relative residual a solve must reach for a --check to trust the run: the loosest
//! pressure tolerance a shipped scene asks for (sediment_transport_3d.yaml; the default is 1e-8,
//! most scenes ask 1e-8 or 1e-10).
inline constexpr double check_max_solve_residual = 1e-6;

//! check_solves_converged for the pressure projection ("pressure_*" columns) of a Runner's run.
template <class RunnerType>
bool check_pressure_converged(const RunnerType& runner, double max_residual = check_max_solve_residual) {
  return check_solves_converged("pressure", runner.history_or_zero("pressure_unconverged"),
                                runner.history_or_zero("pressure_residual"),
                                runner.history_or_zero("pressure_round_off"), max_residual);
}

}  // namespace mpm
