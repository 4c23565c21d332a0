#include <mpm/core/app.h>
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/core/huge_pages.h>
#include <mpm/core/memory_budget.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/stop_signals.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

namespace mpm {

int run_app(int argc, char** argv, const std::string& app_name, const std::string& description,
            const std::function<int(const CommandLine&)>& body) {
  const CommandLine cl = parse_command_line(argc, argv, app_name, description);
  keep_freed_memory();
  if (cl.max_memory_gb) cap_memory(*cl.max_memory_gb * 1e9);
  // Held for the whole run: every parallel loop of the process uses at most this many threads.
  std::optional<tbb::global_control> thread_limit;
  if (cl.threads) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, *cl.threads);
  try {
    const int code = body(cl);
    return code == 0 && cl.check && any_check_failed() ? 1 : code;
  } catch (const StopRequested& e) {
    std::cerr << "\n" << app_name << ": " << e.what() << "\n";
    return 128 + e.signal();
  } catch (const InputError& e) {
    std::cerr << app_name << ": input error: " << e.what() << "\n";
    return 2;
  } catch (const NumericalError& e) {
    std::cerr << "\n" << app_name << ": numerical error: " << e.what() << "\n";
    return 3;
  } catch (const IoError& e) {
    std::cerr << "\n" << app_name << ": I/O error: " << e.what() << "\n";
    return 4;
  } catch (const std::exception& e) {
    std::cerr << "\n" << app_name << ": error: " << e.what() << "\n";
    return 4;
  }
}

int run_scene_app(int argc, char** argv, const std::string& app_name, const std::string& description,
                  SceneRunner run_2d, SceneRunner run_3d) {
  return run_app(argc, argv, app_name, description, [&](const CommandLine& cl) {
    const Config scene = Config::load(cl.scene_file, cl.overrides);
    return scene_dimension(scene) == 2 ? run_2d(cl, scene) : run_3d(cl, scene);
  });
}

namespace {
bool g_check_failed = false;
}  // namespace

bool any_check_failed() { return g_check_failed; }

int worker_threads() {
  return static_cast<int>(
      std::min<std::size_t>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
                            static_cast<std::size_t>(available_cores())));
}

bool check_value(const std::string& name, double value, double expected, double tolerance) {
  const bool ok = std::fabs(value - expected) <= tolerance;
  if (!ok) g_check_failed = true;
  std::fprintf(stderr, "check %s: %.6g (expected %.6g, tolerance %.3g) %s\n", name.c_str(), value, expected, tolerance,
               ok ? "ok" : "FAILED");
  return ok;
}

bool check_solve_residuals(const std::string& solve, const std::vector<double>& residual,
                           const std::vector<double>& round_off, double max_residual) {
  double largest = 0.0;
  std::size_t worst_frame = 0;
  for (std::size_t f = 0; f < residual.size(); ++f) {
    const bool at_round_off = f < round_off.size() && round_off[f] != 0.0;
    // A NaN residual fails and stays the one reported.
    if (!at_round_off && !std::isnan(largest) && (std::isnan(residual[f]) || residual[f] > largest)) {
      largest = residual[f];
      worst_frame = f;
    }
  }
  const bool ok = !std::isnan(largest) && largest <= max_residual;
  if (!ok) g_check_failed = true;
  std::fprintf(stderr,
               "check %s_converged: %.6g (expected residual <= %.3g outside the round-off floor; largest in frame "
               "%zu) %s\n",
               solve.c_str(), largest, max_residual, worst_frame, ok ? "ok" : "FAILED");
  return ok;
}

}  // namespace mpm
