// Preconditioned conjugate gradients (Saad, Iterative Methods for Sparse Linear Systems,
// Alg. 9.1): r = b - A p, z = M r, d = z; alpha = (r.z)/(d.A d), p += alpha d, r -= alpha A d,
// z = M r, d = z + ((r.z)_new/(r.z)_old) d.
#include <fluid/pressure/pcg.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace fluid {

double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

SolveResult pcg(const LinearMap& A, const LinearMap& precondition, const std::vector<double>& b,
                std::vector<double>& p, const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = b.size();
  if (p.size() != n) p.assign(n, 0.0);
  std::vector<double> r(n), z(n), d(n), Ad(n);
  const double b_norm = std::sqrt(dot(b, b));
  if (b_norm == 0.0) std::fill(p.begin(), p.end(), 0.0);  // the exact solution; no relative target exists
  A(p, Ad);
  for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - Ad[i];
  const double target = std::max(control.relative_tolerance * b_norm, control.absolute_tolerance);
  SolveResult result;
  double r_norm = std::sqrt(dot(r, r));
  if (r_norm > target) {
    if (precondition) precondition(r, z); else z = r;
    d = z;
    double rz = dot(r, z);
    while (result.iterations < control.max_iterations) {
      A(d, Ad);
      const double dAd = dot(d, Ad);
      if (!(dAd > 0.0) || !(rz > 0.0)) break;  // breakdown: reported as not converged
      const double alpha = rz / dAd;
      for (std::size_t i = 0; i < n; ++i) {
        p[i] += alpha * d[i];
        r[i] -= alpha * Ad[i];
      }
      ++result.iterations;
      r_norm = std::sqrt(dot(r, r));
      if (r_norm <= target) break;
      if (precondition) precondition(r, z); else z = r;
      const double rz_new = dot(r, z);
      const double beta = rz_new / rz;
      rz = rz_new;
      for (std::size_t i = 0; i < n; ++i) d[i] = z[i] + beta * d[i];
    }
  }
  A(p, Ad);
  for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - Ad[i];
  result.absolute_residual = std::sqrt(dot(r, r));
  result.relative_residual = b_norm > 0.0 ? result.absolute_residual / b_norm : 0.0;
  // The true residual may sit slightly above the recurrence one; allow a factor 10 of drift.
  result.converged = std::isfinite(result.absolute_residual) && result.absolute_residual <= 10.0 * target;
  result.solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace fluid
