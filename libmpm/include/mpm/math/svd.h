#pragma once
//! Rotation-variant SVD and polar decomposition of 2x2 and 3x3 matrices.
//!
//! F = U diag(sigma) V^T with U and V proper rotations (det = +1). The singular values are
//! ordered |sigma_0| >= ... >= |sigma_{d-1}|; all are >= 0 except the last, which carries the
//! sign of det F. An inverted F (det F < 0) therefore keeps rotations in U and V and shows up
//! as one negative singular value, which is what invertible elasticity needs (Irving et al.
//! 2004; Stomakhin et al. 2012): R = U V^T is the closest proper rotation to F also when F is
//! inverted. In 2D a closed form is exact (svd2); in 3D svd3 follows McAdams et al. 2011
//! (Jacobi eigenanalysis of F^T F, then a QR of F V), about 2.3 times faster than Eigen's
//! general two-sided Jacobi SVD (docs/performance.md), which the 3D models and return maps
//! used to call twice per particle per step.
#include <mpm/core/types.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace mpm::math {

template <int dim>
struct Svd {
  Mat<dim> U;
  Vec<dim> sigma;
  Mat<dim> V;
};

//! Polar decomposition F = R S, R a proper rotation, S symmetric (indefinite when det F < 0).
template <int dim>
struct Polar {
  Mat<dim> R;
  Mat<dim> S;
};

//! Closed-form 2x2 SVD: the polar rotation R(theta), theta = atan2(F10 - F01, F00 + F11),
//! makes S = R^T F symmetric with tr S >= 0; one Jacobi rotation V(phi), phi = atan2(2 S01,
//! S00 - S11) / 2, diagonalises S with eigenvalues s0 >= s1 and s0 + s1 >= 0, so |s0| >= |s1|
//! and only s1 can be negative. Then F = (R V) diag(s) V^T.
inline Svd<2> svd2(const Mat<2>& F) {
  const double theta = std::atan2(F(1, 0) - F(0, 1), F(0, 0) + F(1, 1));
  const double c = std::cos(theta), s = std::sin(theta);
  const double s00 = c * F(0, 0) + s * F(1, 0), s11 = -s * F(0, 1) + c * F(1, 1);
  const double s01 = c * F(0, 1) + s * F(1, 1);
  const double phi = 0.5 * std::atan2(2.0 * s01, s00 - s11);
  const double cp = std::cos(phi), sp = std::sin(phi);
  const double mean = 0.5 * (s00 + s11), radius = std::hypot(0.5 * (s00 - s11), s01);
  Svd<2> r;
  r.V << cp, -sp, sp, cp;
  r.sigma << mean + radius, mean - radius;
  Mat<2> R;
  R << c, -s, s, c;
  r.U = R * r.V;
  return r;
}

namespace detail {

//! 2^k for -1022 <= k <= 1023, exact, from the exponent bits (std::ldexp is a library call).
inline double power_of_two(int k) { return std::bit_cast<double>(static_cast<std::uint64_t>(k + 1023) << 52); }

//! The exponent e of x = m 2^e, m in [1/2, 1), as std::frexp gives it, read from the bits of a
//! normal x > 0 (std::frexp for a subnormal one).
inline int binary_exponent(double x) {
  const int biased = static_cast<int>((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7ff);
  if (biased == 0) {
    int e = 0;
    std::frexp(x, &e);
    return e;
  }
  return biased - 1022;
}

//! Jacobi sweeps (three rotations each) are repeated until ||off(S)|| <= eps ||diag S||; random
//! matrices need 3 or 4 (quadratic convergence). The cap only bounds the loop.
inline constexpr int kMaxJacobiSweeps = 12;

//! One Jacobi rotation in the (p, q) plane that zeroes S(p, q): S <- J^T S J, V <- V J, with
//! the angle of the symmetric 2x2 Schur decomposition (Golub and Van Loan, sec. 8.5.2) of
//! [S_pp S_pq; S_pq S_qq], the smaller of the two (|t| <= 1). With d = S_qq - S_pp and
//! r = sqrt(d^2 + 4 S_pq^2), t = tan(theta) = 2 S_pq sign(d) / (|d| + r) and
//! c = cos(theta) = (|d| + r) / sqrt(2 r (|d| + r)): two square roots and no division by S_pq.
//! Once t^2 < eps / 2, which is the case in the last sweep, c rounds to 1 and t to S_pq / d,
//! so both roots are skipped without changing the result. S is scaled (svd3), so an S_pq below
//! 1e-150 is far below round-off of S and is dropped without a rotation.
inline void jacobi_rotate(Mat<3>& S, Mat<3>& V, int p, int q) {
  const int r = 3 - p - q;
  const double spq = S(p, q), d = S(q, q) - S(p, p);
  double t = 0.0, c = 1.0, s = 0.0;
  if (spq * spq < 0.5 * std::numeric_limits<double>::epsilon() * d * d) {
    t = spq / d;
    s = t;
  } else if (std::abs(spq) > 1e-150) {
    const double radius = std::sqrt(d * d + 4.0 * spq * spq);
    const double twice_spq = std::copysign(2.0, d) * spq;
    const double sum = std::abs(d) + radius;
    const double inverse_norm = 1.0 / std::sqrt(2.0 * radius * sum);
    t = twice_spq / sum;
    c = sum * inverse_norm;
    s = twice_spq * inverse_norm;
  }
  S(p, p) -= t * spq;
  S(q, q) += t * spq;
  S(p, q) = S(q, p) = 0.0;
  const double srp = S(r, p), srq = S(r, q);
  S(r, p) = S(p, r) = c * srp - s * srq;
  S(r, q) = S(q, r) = s * srp + c * srq;
  for (int i = 0; i < 3; ++i) {
    const double vp = V(i, p), vq = V(i, q);
    V(i, p) = c * vp - s * vq;
    V(i, q) = s * vp + c * vq;
  }
}

//! Exchanges columns a and b of B and V and negates the new column b of both, so that V stays a
//! rotation and B = F V still holds.
inline void swap_columns(Mat<3>& B, Mat<3>& V, int a, int b) {
  B.col(a).swap(B.col(b));
  V.col(a).swap(V.col(b));
  B.col(b) *= -1.0;
  V.col(b) *= -1.0;
}

//! A Givens rotation on rows p and q that zeroes R(q, column) into R(p, column) >= 0, applied to
//! the remaining columns of R and accumulated into U (B = U R throughout).
inline void givens_eliminate(Mat<3>& R, Mat<3>& U, int p, int q, int column) {
  const double a = R(p, column), b = R(q, column);
  const double r = std::sqrt(a * a + b * b), inverse_r = 1.0 / r;
  // r = 0: nothing to eliminate (a and b are zero or below the square's underflow).
  const double c = r > 0.0 ? a * inverse_r : 1.0, s = r > 0.0 ? b * inverse_r : 0.0;
  for (int j = column; j < 3; ++j) {
    const double rp = R(p, j), rq = R(q, j);
    R(p, j) = c * rp + s * rq;
    R(q, j) = -s * rp + c * rq;
  }
  R(q, column) = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double up = U(i, p), uq = U(i, q);
    U(i, p) = c * up + s * uq;
    U(i, q) = -s * up + c * uq;
  }
}

//! Puts sigma(0) >= sigma(1) (both >= 0) in order, keeping U diag(sigma) V^T and det U = det V.
inline void order_first(Svd<3>& f) {
  if (f.sigma(0) >= f.sigma(1)) return;
  std::swap(f.sigma(0), f.sigma(1));
  f.U.col(0).swap(f.U.col(1));
  f.V.col(0).swap(f.V.col(1));
  f.U.col(1) *= -1.0;
  f.V.col(1) *= -1.0;
}

//! Puts sigma(1) >= |sigma(2)| in order; the sign of det F stays on sigma(2).
inline void order_last(Svd<3>& f) {
  if (f.sigma(1) >= std::abs(f.sigma(2))) return;
  const double sign = f.sigma(2) < 0.0 ? -1.0 : 1.0;
  const double larger = std::abs(f.sigma(2)), smaller = sign * f.sigma(1);
  f.sigma(1) = larger;
  f.sigma(2) = smaller;
  f.U.col(1).swap(f.U.col(2));
  f.V.col(1).swap(f.V.col(2));
  f.U.col(1) *= sign;
  f.U.col(2) *= -sign;
  f.V.col(2) *= -1.0;
}

}  // namespace detail

//! 3x3 SVD after McAdams et al. 2011, "Computing the singular value decomposition of 3x3
//! matrices with minimal branching and elementary floating point operations": Jacobi
//! eigenanalysis of S = F^T F gives V, the columns of B = F V are sorted by decreasing norm, and
//! a Givens QR B = U R gives U and sigma = diag R. A fixed sequence of 3x3 operations instead of
//! a general SVD. Unlike the paper (single precision, four sweeps of approximate Givens
//! angles), the rotations are exact and the sweeps repeat until the off-diagonal part of S is at
//! round-off, so that the factors are accurate in double.
inline Svd<3> svd3(const Mat<3>& F) {
  Svd<3> f{Mat<3>::Identity(), Vec<3>::Zero(), Mat<3>::Identity()};
  const double largest = F.cwiseAbs().maxCoeff();
  if (largest == 0.0) return f;
  // Scaling by a power of two (exact) to a largest entry in [1/2, 1) keeps S = A^T A and the
  // squares below far from overflow and underflow for any finite F. Two factors keep 2^-exponent
  // representable also for subnormal and huge entries.
  const int exponent = detail::binary_exponent(largest);
  const Mat<3> A = F * detail::power_of_two(-exponent / 2) * detail::power_of_two(exponent / 2 - exponent);

  Mat<3> S = A.transpose() * A;
  const double squared_tolerance = std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();
  for (int sweep = 0; sweep < detail::kMaxJacobiSweeps; ++sweep) {
    const double off = S(0, 1) * S(0, 1) + S(0, 2) * S(0, 2) + S(1, 2) * S(1, 2);
    if (off <= squared_tolerance * S.diagonal().squaredNorm()) break;
    detail::jacobi_rotate(S, f.V, 0, 1);
    detail::jacobi_rotate(S, f.V, 0, 2);
    detail::jacobi_rotate(S, f.V, 1, 2);
  }

  // Column pivoting (largest norm first) makes the QR below rank revealing.
  Mat<3> R = A * f.V;
  Vec<3> norms = R.colwise().squaredNorm().transpose();
  for (const auto& [a, b] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) {
    if (norms(a) >= norms(b)) continue;
    detail::swap_columns(R, f.V, a, b);
    std::swap(norms(a), norms(b));
  }

  detail::givens_eliminate(R, f.U, 0, 1, 0);
  detail::givens_eliminate(R, f.U, 0, 2, 0);
  detail::givens_eliminate(R, f.U, 1, 2, 1);
  f.sigma = R.diagonal();

  // S = F^T F holds singular values below sqrt(eps) sigma_0 only to round-off of sigma_0^2, so
  // when two of them are that small their right vectors mix and R(1, 2) is not negligible.
  // The lower 2x2 block of R has them at their own scale: its closed-form SVD finishes them.
  if (std::abs(R(1, 2)) > 4.0 * std::numeric_limits<double>::epsilon() * R(0, 0)) {
    const auto block = svd2(Mat<2>(R.bottomRightCorner<2, 2>()));
    f.U.rightCols<2>() = f.U.rightCols<2>() * block.U;
    f.V.rightCols<2>() = f.V.rightCols<2>() * block.V;
    f.sigma.tail<2>() = block.sigma;
  }

  // R's diagonal follows the column norms only up to round-off; ties (repeated singular values)
  // can come out one ulp out of order.
  detail::order_first(f);
  detail::order_last(f);
  detail::order_first(f);
  f.sigma = f.sigma * detail::power_of_two(exponent - exponent / 2) * detail::power_of_two(exponent / 2);
  return f;
}

template <int dim>
Svd<dim> svd(const Mat<dim>& F) {
  if constexpr (dim == 2) {
    return svd2(F);
  } else {
    return svd3(F);
  }
}

template <int dim>
Polar<dim> polar(const Mat<dim>& F) {
  const Svd<dim> f = svd(F);
  return {f.U * f.V.transpose(), f.V * f.sigma.asDiagonal() * f.V.transpose()};
}

}  // namespace mpm::math
