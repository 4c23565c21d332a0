#pragma once
//! The preconditioners that need nothing but the operator's diagonal. A preconditioner is any
//! object with apply(r, z), z = M r, for a symmetric positive (semi-)definite M; the geometric
//! and the modulated multigrid of libfluid are others (fluid/pressure/multigrid.h).
#include <mpm/core/solve/vector_space.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace mpm::solve {

//! M = I: plain conjugate gradients.
struct IdentityPreconditioner {
  template <class Vector>
  void apply(const Vector& r, Vector& z) const {
    z = r;
  }
};

//! M = diag(A)^-1, applied as a product with the stored inverse (a division per entry and
//! iteration would cost more than the rest of the preconditioner). A zero diagonal entry (a row
//! of A that is zero, e.g. a cell cut off from every degree of freedom) gives z = 0 there, which
//! keeps M semi-definite.
class JacobiPreconditioner {
public:
  explicit JacobiPreconditioner(std::vector<double> diagonal) : inverse_(std::move(diagonal)) {
    for (double& d : inverse_) d = d > 0.0 ? 1.0 / d : 0.0;
  }

  template <class T>
  void apply(const std::vector<T>& r, std::vector<T>& z) const {
    z.resize(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) z[i] = inverse_[i] * r[i];
  }

private:
  std::vector<double> inverse_;
};

}  // namespace mpm::solve
