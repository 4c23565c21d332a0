#pragma once
//! Preconditioned conjugate gradients (Saad, Iterative Methods for Sparse Linear Systems,
//! Alg. 9.1), the one Krylov solver of the project: the pressure back-ends, the implicit
//! viscosity and every later implicit stage call it with their own operator and
//! preconditioner (OpenVDB math/ConjGradient.h, AMReX MLMG keep them apart likewise):
//!   r = b - A x, z = M r, d = z; alpha = (r.z) / (d.A d), x += alpha d, r -= alpha A d,
//!   z = M r, d = z + ((r.z)_new / (r.z)_old) d.
//! The operator and the preconditioner are objects with apply(in, out) or callables
//! f(in, out). Vector is std::vector<T>, T a scalar or a fixed-size Eigen vector
//! (vector_space.h).
//!
//! Works for a singular A when b lies in its range and M is symmetric positive semi-definite
//! and positive on range(A) (the NodeCell pressure operator): iterates then differ from a
//! solution only by null-space components. The stopping test uses the recurrence residual; the
//! result reports the true residual |b - A x|, recomputed at the end, and counts as converged
//! when it lies within a factor 10 of the target (the recurrence drifts from it by round-off).
//! A breakdown (d.A d <= 0 or r.z <= 0: A or M not positive on the Krylov space, or NaN) stops
//! the iteration and is reported as not converged.
#include <mpm/core/error.h>
#include <mpm/core/solve/solve_control.h>
#include <mpm/core/solve/vector_space.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <type_traits>

namespace mpm::solve {

//! out = L in, for an object with apply() or a callable.
template <class Map, class Vector>
void apply(Map& map, const Vector& in, Vector& out) {
  if constexpr (std::is_invocable_v<Map&, const Vector&, Vector&>)
    map(in, out);
  else
    map.apply(in, out);
}

//! Solves A x = b from the initial guess in x (resized to b with zeros when its size differs).
//! Setup seconds are left 0: the caller owns the preconditioner's set-up.
template <class Vector, class Operator, class Preconditioner>
SolveResult conjugate_gradient(Operator&& A, Preconditioner&& M, const Vector& b, Vector& x,
                               const SolveControl& control) {
  using T = typename Vector::value_type;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = b.size();
  if (x.size() != n) x.assign(n, zero<T>());
  Vector r(n), z(n), d(n), Ad(n);
  const double b_norm = std::sqrt(dot(b, b));
  MPM_ASSERT(std::isfinite(b_norm));
  if (b_norm == 0.0) std::fill(x.begin(), x.end(), zero<T>());  // the exact solution; no relative target exists
  apply(A, x, Ad);
  for_each_entry(n, [&](std::size_t i) { r[i] = b[i] - Ad[i]; });
  const double target = std::max(control.relative_tolerance * b_norm, control.absolute_tolerance);
  SolveResult result;
  if (std::sqrt(dot(r, r)) > target) {
    apply(M, r, z);
    for_each_entry(n, [&](std::size_t i) { d[i] = z[i]; });
    double rz = dot(r, z);
    while (result.iterations < control.max_iterations) {
      apply(A, d, Ad);
      const double dAd = dot(d, Ad);
      if (!(dAd > 0.0) || !(rz > 0.0)) {
        result.breakdown = true;
        break;
      }
      const double alpha = rz / dAd;
      for_each_entry(n, [&](std::size_t i) {
        x[i] += alpha * d[i];
        r[i] -= alpha * Ad[i];
      });
      ++result.iterations;
      if (std::sqrt(dot(r, r)) <= target) break;
      apply(M, r, z);
      const double rz_new = dot(r, z);
      const double beta = rz_new / rz;
      rz = rz_new;
      for_each_entry(n, [&](std::size_t i) { d[i] = z[i] + beta * d[i]; });
    }
  }
  apply(A, x, Ad);
  for_each_entry(n, [&](std::size_t i) { r[i] = b[i] - Ad[i]; });
  result.absolute_residual = std::sqrt(dot(r, r));
  result.relative_residual = b_norm > 0.0 ? result.absolute_residual / b_norm : 0.0;
  result.converged = std::isfinite(result.absolute_residual) && result.absolute_residual <= 10.0 * target;
  result.solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace mpm::solve
