#pragma once
//! Observed order of convergence for the verification tests: the least-squares slope of
//! log(error) against log(dx) over all refinement levels (MFEM tests/convergence/rates.cpp
//! prints the ratio of successive levels; one fit over >= 4 levels is less sensitive to a
//! single pre-asymptotic level), and the table printed for docs/verification.md.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace mpm::verification {

struct Level {
  int cells = 0;         //!< cells across the reference length
  double dx = 0.0;       //!< [m]
  double error = 0.0;    //!< the test's error norm (dimensionless or [m], see the test)
  double seconds = 0.0;  //!< wall time of the run [s]
};

//! Slope p of the least-squares line log(error) = p log(dx) + q.
inline double observed_order(const std::vector<Level>& levels) {
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  const double n = static_cast<double>(levels.size());
  for (const Level& l : levels) {
    const double x = std::log(l.dx), y = std::log(l.error);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

//! Markdown table of the levels and the fitted order, on stdout.
inline void print_table(const std::string& title, const std::vector<Level>& levels) {
  std::printf("\n%s\n| cells | dx [m] | error | ratio | run time [s] |\n|---:|---:|---:|---:|---:|\n", title.c_str());
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const Level& l = levels[i];
    if (i == 0)
      std::printf("| %d | %.5g | %.4e | | %.2f |\n", l.cells, l.dx, l.error, l.seconds);
    else
      std::printf("| %d | %.5g | %.4e | %.2f | %.2f |\n", l.cells, l.dx, l.error, levels[i - 1].error / l.error,
                  l.seconds);
  }
  std::printf("observed order (least squares over %zu levels): %.3f\n", levels.size(), observed_order(levels));
}

}  // namespace mpm::verification
