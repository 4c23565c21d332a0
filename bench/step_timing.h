#pragma once
// The timing half of bench_step, shared by its solid cases (bench_step.cpp) and its fluid and
// coupled cases (bench_step_coupled.cpp): runs of the library at each thread count alternate
// with the reference's, the medians and the stage split of the last run are printed.
#include <mpm/core/pipeline.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace bench {

using Clock = std::chrono::steady_clock;

//! A number for a scene's YAML text that reads back as the same double (17 significant digits):
//! a reference that computes dx = 1 / cells itself must get the grid the library parses.
inline std::string yaml_number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.17g", v);
  return s;
}

inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

//! The largest difference of the totals a and b, each relative to the largest magnitude in its
//! group (entries [first, end) of each pair of `groups`): how a run's totals and the
//! reference's are compared.
inline double max_group_difference(const std::vector<double>& a, const std::vector<double>& b,
                                   const std::vector<std::pair<int, int>>& groups) {
  double d = 0;
  for (const auto& [first, end] : groups) {
    double scale = 0;
    for (int i = first; i < end; ++i) scale = std::max({scale, std::abs(a[i]), std::abs(b[i])});
    for (int i = first; i < end; ++i) d = std::max(d, scale > 0 ? std::abs(a[i] - b[i]) / scale : 0.0);
  }
  return d;
}

//! One timed run of the library: wall seconds of the steps and its stage times.
struct StepRun {
  double seconds = 0;
  mpm::StageTimes stages;
};

//! Times `reference()` (its own thread count) and `library()` at each of `threads` (the first
//! is 1), `repeat` times alternating, and prints the medians in ns per particle-step per core
//! (seconds x threads x 1e9 / particle_steps), the ratio to the reference, the speed-up over one
//! thread and the stage split of the last run at the most threads.
inline void time_and_report(const std::vector<int>& threads, int repeat, double particle_steps,
                            const std::function<double()>& reference, const std::function<StepRun()>& library) {
  std::vector<double> ref;
  std::vector<std::vector<double>> lib(threads.size());
  mpm::StageTimes stages;
  for (int r = 0; r < repeat; ++r) {
    ref.push_back(reference());
    for (std::size_t i = 0; i < threads.size(); ++i) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads[i]);
      StepRun run = library();
      lib[i].push_back(run.seconds);
      stages = std::move(run.stages);
    }
  }
  const double ref_s = median(ref), one = median(lib[0]);
  std::printf("median of %d runs; ns per particle-step per core = s x threads x 1e9 / (particles x steps)\n", repeat);
  std::printf("%-10s %7s | %9s %14s %12s %9s\n", "run", "threads", "s", "ns/p-step/core", "vs reference", "speed-up");
  std::printf("%-10s %7d | %9.3f %14.1f %12s %9s\n", "reference", 1, ref_s, ref_s * 1e9 / particle_steps, "1.00", "");
  for (std::size_t i = 0; i < threads.size(); ++i) {
    const double s = median(lib[i]);
    std::printf("%-10s %7d | %9.3f %14.1f %12.2f %9.2f\n", "library", threads[i], s,
                s * threads[i] * 1e9 / particle_steps, ref_s / s, one / s);
  }
  std::printf("library stages at %d thread%s (last run, ns per particle-step):", threads.back(),
              threads.back() > 1 ? "s" : "");
  for (std::size_t k = 0; k < stages.names.size(); ++k)
    std::printf(" %s %.1f", stages.names[k].c_str(), stages.seconds[k] * 1e9 / particle_steps);
  std::printf("\n");
}

//! The fluid and coupled cases (bench_step_coupled.cpp; only in builds with libcoupling):
//! returns false when the library's run and the reference's disagree. `setup_reuse`: the
//! library's pressure.setup_reuse.
bool run_coupled_case(const std::string& name, int cells, int steps, int repeat, const std::vector<int>& threads,
                      int setup_reuse);

}  // namespace bench
