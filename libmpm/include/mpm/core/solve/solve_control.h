#pragma once
//! The stopping criteria of an iterative solve and its outcome (OpenVDB's ConjGradient State
//! split in two: the control goes in, the result comes out). A solve never fails silently: the
//! caller reads `converged` and decides whether the step warns or stops.
namespace mpm::solve {

//! What a scene decides about a solve that did not converge: go on with a warning, or stop.
enum class OnFailure { warn, stop };

struct SolveControl {
  double relative_tolerance = 1e-8;  //!< stop when |b - A x| <= rtol |b|
  double absolute_tolerance = 0.0;   //!< ... or when |b - A x| <= atol
  int max_iterations = 1000;
};

struct SolveResult {
  bool converged = false;
  //! The iteration stopped on a breakdown (CG: d.A d <= 0 or r.z <= 0, the operator or the
  //! preconditioner not positive on the Krylov space, or NaN), not on the tolerance or the cap.
  bool breakdown = false;
  int iterations = 0;
  double relative_residual = 0.0;  //!< |b - A x| / |b| (0 when b = 0)
  double absolute_residual = 0.0;
  double setup_seconds = 0.0;  //!< preconditioner or factorisation set-up, filled by the caller
  double solve_seconds = 0.0;
};

}  // namespace mpm::solve
