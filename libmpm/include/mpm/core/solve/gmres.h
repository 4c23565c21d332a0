#pragma once
//! Restarted GMRES(m) with right preconditioning (Saad, Iterative Methods for Sparse Linear
//! Systems, Alg. 6.11 with 9.5): the Krylov solver for the non-symmetric systems of the
//! project (the Newton systems of a solid whose return map acts inside the step). It
//! minimises |b - A x| over x0 + M K_m(A M, r0) in every cycle, so the residual never grows:
//! a truncated solve still gives an inexact Newton step that descends on |g|^2 (Eisenstat and
//! Walker 1994), which BiCGSTAB's erratic residual does not. Arnoldi by modified Gram-Schmidt,
//! the least-squares problem by Givens rotations. Same interfaces and result as
//! conjugate_gradient (conjugate_gradient.h); `restart` is m.
#include <mpm/core/solve/conjugate_gradient.h>

#include <vector>

namespace mpm::solve {

template <class Vector, class Operator, class Preconditioner>
SolveResult gmres(Operator&& A, Preconditioner&& M, const Vector& b, Vector& x, const SolveControl& control,
                  int restart = 30) {
  using T = typename Vector::value_type;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = b.size();
  const int m = std::max(restart, 1);
  if (x.size() != n) x.assign(n, zero<T>());
  const double b_norm = std::sqrt(dot(b, b));
  MPM_ASSERT(std::isfinite(b_norm));
  if (b_norm == 0.0) std::fill(x.begin(), x.end(), zero<T>());
  const double target = std::max(control.relative_tolerance * b_norm, control.absolute_tolerance);
  Vector r(n), w(n), z(n);
  std::vector<Vector> V(static_cast<std::size_t>(m) + 1, Vector(n));
  std::vector<std::vector<double>> H(static_cast<std::size_t>(m) + 1, std::vector<double>(m, 0.0));
  std::vector<double> cs(m), sn(m), g(static_cast<std::size_t>(m) + 1);
  const auto residual = [&] {
    apply(A, x, w);
    for (std::size_t i = 0; i < n; ++i) r[i] = b[i] - w[i];
    return std::sqrt(dot(r, r));
  };
  SolveResult result;
  double beta = residual();
  while (beta > target && std::isfinite(beta) && result.iterations < control.max_iterations) {
    for (std::size_t i = 0; i < n; ++i) V[0][i] = r[i] / beta;
    std::fill(g.begin(), g.end(), 0.0);
    g[0] = beta;
    int k = 0;  // Arnoldi vectors of this cycle
    for (int j = 0; j < m && result.iterations < control.max_iterations; ++j) {
      apply(M, V[j], z);
      apply(A, z, w);
      for (int i = 0; i <= j; ++i) {
        H[i][j] = dot(w, V[i]);
        for (std::size_t q = 0; q < n; ++q) w[q] -= H[i][j] * V[i][q];
      }
      H[j + 1][j] = std::sqrt(dot(w, w));
      for (int i = 0; i < j; ++i) {  // the earlier rotations on the new column
        const double h = cs[i] * H[i][j] + sn[i] * H[i + 1][j];
        H[i + 1][j] = -sn[i] * H[i][j] + cs[i] * H[i + 1][j];
        H[i][j] = h;
      }
      const double radius = std::hypot(H[j][j], H[j + 1][j]);
      const double breakdown = H[j + 1][j];
      cs[j] = radius > 0.0 ? H[j][j] / radius : 1.0;
      sn[j] = radius > 0.0 ? H[j + 1][j] / radius : 0.0;
      H[j][j] = radius;
      H[j + 1][j] = 0.0;
      g[j + 1] = -sn[j] * g[j];
      g[j] *= cs[j];
      ++result.iterations;
      k = j + 1;
      if (std::abs(g[j + 1]) <= target || !(breakdown > 0.0) || !(radius > 0.0)) break;
      for (std::size_t q = 0; q < n; ++q) V[j + 1][q] = w[q] / breakdown;
    }
    // y = H^-1 g (upper triangular), x += M V y.
    std::vector<double> y(k);
    for (int i = k - 1; i >= 0; --i) {
      double s = g[i];
      for (int j = i + 1; j < k; ++j) s -= H[i][j] * y[j];
      y[i] = H[i][i] != 0.0 ? s / H[i][i] : 0.0;
    }
    std::fill(w.begin(), w.end(), zero<T>());
    for (int i = 0; i < k; ++i)
      for (std::size_t q = 0; q < n; ++q) w[q] += y[i] * V[i][q];
    apply(M, w, z);
    for (std::size_t q = 0; q < n; ++q) x[q] += z[q];
    const double previous = beta;
    beta = residual();
    if (!(beta < previous)) break;  // stagnation (or a breakdown with nothing gained)
  }
  result.absolute_residual = residual();
  result.relative_residual = b_norm > 0.0 ? result.absolute_residual / b_norm : 0.0;
  result.converged = std::isfinite(result.absolute_residual) && result.absolute_residual <= 10.0 * target;
  result.solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace mpm::solve
