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
//! used to call twice per particle per step. The per-particle loops take four SVDs at once
//! (for_each_svd: the same operations in four lanes, each lane's result bit for bit svd3's),
//! about 2.2 times faster again per matrix.
#include <mpm/core/types.h>
#include <mpm/math/detail/lanes.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
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

//! A 3x3 matrix of T: one double (one matrix) or Lanes (four matrices, lanes.h).
template <class T>
struct Mat3 {
  T a[3][3];
  T& operator()(int i, int j) { return a[i][j]; }
  const T& operator()(int i, int j) const { return a[i][j]; }
};

//! One Jacobi rotation in the (p, q) plane that zeroes S(p, q): S <- J^T S J, V <- V J, with
//! the angle of the symmetric 2x2 Schur decomposition (Golub and Van Loan, sec. 8.5.2) of
//! [S_pp S_pq; S_pq S_qq], the smaller of the two (|t| <= 1). With d = S_qq - S_pp and
//! r = sqrt(d^2 + 4 S_pq^2), t = tan(theta) = 2 S_pq sign(d) / (|d| + r) and
//! c = cos(theta) = (|d| + r) / sqrt(2 r (|d| + r)): two square roots and no division by S_pq.
//! Once t^2 < eps / 2, which is the case in the last sweep, c rounds to 1 and t to S_pq / d,
//! so both roots are skipped without changing the result (one matrix; four lanes compute both
//! and select). S is scaled (svd3), so an S_pq below 1e-150 is far below round-off of S and is
//! dropped without a rotation. Lanes not `active` (converged) are left as they are.
template <class T, class Mask>
[[gnu::always_inline]] inline void jacobi_rotate(Mat3<T>& S, Mat3<T>& V, int p, int q, Mask active) {
  const int r = 3 - p - q;
  const T spq = S(p, q), d = S(q, q) - S(p, p);
  const auto cheap = spq * spq < 0.5 * std::numeric_limits<double>::epsilon() * d * d;
  const auto rotate = [&] {  // t, c, s of the full formula
    const T radius = lane_sqrt(d * d + 4.0 * spq * spq);
    const T twice_spq = lane_copysign(T(2.0), d) * spq;
    const T sum = lane_abs(d) + radius;
    const T inverse_norm = 1.0 / lane_sqrt(2.0 * radius * sum);
    return std::array<T, 3>{twice_spq / sum, sum * inverse_norm, twice_spq * inverse_norm};
  };
  T t = 0.0, c = 1.0, s = 0.0;
  if constexpr (kOneLane<T>) {
    if (cheap) {
      t = spq / d;
      s = t;
    } else if (std::abs(spq) > 1e-150) {
      const auto [tf, cf, sf] = rotate();
      t = tf;
      c = cf;
      s = sf;
    }
  } else {
    const auto full = rotate();
    const auto turn = active & (cheap | (lane_abs(spq) > T(1e-150)));
    const T ratio = spq / d;
    t = select(turn, select(cheap, ratio, full[0]), T(0.0));
    c = select(turn, select(cheap, T(1.0), full[1]), T(1.0));
    s = select(turn, select(cheap, ratio, full[2]), T(0.0));
  }
  S(p, p) -= t * spq;
  S(q, q) += t * spq;
  S(p, q) = S(q, p) = select(active, T(0.0), spq);
  const T srp = S(r, p), srq = S(r, q);
  S(r, p) = S(p, r) = c * srp - s * srq;
  S(r, q) = S(q, r) = s * srp + c * srq;
  for (int i = 0; i < 3; ++i) {
    const T vp = V(i, p), vq = V(i, q);
    V(i, p) = c * vp - s * vq;
    V(i, q) = s * vp + c * vq;
  }
}

//! Where `exchange`, exchanges columns a and b of B and V and negates the new column b of both,
//! so that V stays a rotation and B = F V still holds.
template <class T, class Mask>
[[gnu::always_inline]] inline void swap_columns(Mat3<T>& B, Mat3<T>& V, int a, int b, Mask exchange) {
  for (Mat3<T>* M : {&B, &V})
    for (int i = 0; i < 3; ++i) {
      const T ma = (*M)(i, a), mb = (*M)(i, b);
      (*M)(i, a) = select(exchange, mb, ma);
      (*M)(i, b) = select(exchange, -ma, mb);
    }
}

//! A Givens rotation on rows p and q that zeroes R(q, column) into R(p, column) >= 0, applied to
//! the remaining columns of R and accumulated into U (B = U R throughout).
template <class T>
[[gnu::always_inline]] inline void givens_eliminate(Mat3<T>& R, Mat3<T>& U, int p, int q, int column) {
  const T a = R(p, column), b = R(q, column);
  const T r = lane_sqrt(a * a + b * b), inverse_r = 1.0 / r;
  // r = 0: nothing to eliminate (a and b are zero or below the square's underflow).
  const auto nonzero = r > T(0.0);
  const T c = select(nonzero, a * inverse_r, T(1.0)), s = select(nonzero, b * inverse_r, T(0.0));
  for (int j = column; j < 3; ++j) {
    const T rp = R(p, j), rq = R(q, j);
    R(p, j) = c * rp + s * rq;
    R(q, j) = -s * rp + c * rq;
  }
  R(q, column) = 0.0;
  for (int i = 0; i < 3; ++i) {
    const T up = U(i, p), uq = U(i, q);
    U(i, p) = c * up + s * uq;
    U(i, q) = -s * up + c * uq;
  }
}

//! The factors of svd3 before the finish (svd3_finish): V from the Jacobi eigenanalysis of
//! S = A^T A, the columns of A V sorted by decreasing norm, and its Givens QR A V = U R.
template <class T>
void svd3_factors(const Mat3<T>& A, Mat3<T>& U, Mat3<T>& V, Mat3<T>& R) {
  Mat3<T> S;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      S(i, j) = A(0, i) * A(0, j) + A(1, i) * A(1, j) + A(2, i) * A(2, j);
      U(i, j) = V(i, j) = i == j ? 1.0 : 0.0;
    }
  const double squared_tolerance = std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();
  for (int sweep = 0; sweep < kMaxJacobiSweeps; ++sweep) {
    const T off = S(0, 1) * S(0, 1) + S(0, 2) * S(0, 2) + S(1, 2) * S(1, 2);
    const T diagonal = S(0, 0) * S(0, 0) + S(1, 1) * S(1, 1) + S(2, 2) * S(2, 2);
    const auto active = negate(off <= squared_tolerance * diagonal);
    if (!any(active)) break;
    jacobi_rotate(S, V, 0, 1, active);
    jacobi_rotate(S, V, 0, 2, active);
    jacobi_rotate(S, V, 1, 2, active);
  }

  // Column pivoting (largest norm first) makes the QR below rank revealing.
  T norms[3];
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) R(i, j) = A(i, 0) * V(0, j) + A(i, 1) * V(1, j) + A(i, 2) * V(2, j);
    norms[j] = R(0, j) * R(0, j) + R(1, j) * R(1, j) + R(2, j) * R(2, j);
  }
  for (const auto& [a, b] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) {
    const auto exchange = negate(norms[a] >= norms[b]);
    swap_columns(R, V, a, b, exchange);
    const T na = norms[a];
    norms[a] = select(exchange, norms[b], na);
    norms[b] = select(exchange, na, norms[b]);
  }

  givens_eliminate(R, U, 0, 1, 0);
  givens_eliminate(R, U, 0, 2, 0);
  givens_eliminate(R, U, 1, 2, 1);
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

//! F scaled by a power of two (exact) to a largest entry in [1/2, 1), which keeps S = A^T A and
//! the squares of the rotations far from overflow and underflow for any finite F; two factors
//! keep 2^-exponent representable also for subnormal and huge entries. svd3_finish undoes it.
inline Mat<3> scaled_to_unit(const Mat<3>& F, int& exponent) {
  double largest = 0.0;
  for (int k = 0; k < 9; ++k) largest = std::max(largest, std::abs(F(k)));
  exponent = binary_exponent(largest);  // 0 for F = 0
  const double first = power_of_two(-exponent / 2), second = power_of_two(exponent / 2 - exponent);
  Mat<3> A;
  for (int k = 0; k < 9; ++k) A(k) = F(k) * first * second;
  return A;
}

//! The SVD from the factors of svd3_factors: sigma = diag R, the two smallest singular values
//! redone where F^T F could not resolve them, the order of math/svd.h, the scale back.
inline Svd<3> svd3_finish(const Mat<3>& U, const Mat<3>& V, const Mat<3>& R, int exponent) {
  Svd<3> f{U, R.diagonal(), V};
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
  order_first(f);
  order_last(f);
  order_first(f);
  f.sigma = f.sigma * power_of_two(exponent - exponent / 2) * power_of_two(exponent / 2);
  return f;
}

inline Mat<3> to_matrix(const Mat3<double>& M) {
  Mat<3> m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = M(i, j);
  return m;
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
  int exponent = 0;
  const Mat<3> scaled = detail::scaled_to_unit(F, exponent);
  detail::Mat3<double> A, U, V, R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A(i, j) = scaled(i, j);
  detail::svd3_factors(A, U, V, R);
  return detail::svd3_finish(detail::to_matrix(U), detail::to_matrix(V), detail::to_matrix(R), exponent);
}

//! Matrices per svd3 of several (below): the lanes of detail::Lanes.
inline constexpr int kSvdLanes = 4;

//! The SVDs of four matrices at once (a null pointer: an unused lane), each the same bit for
//! bit as svd3 of that matrix alone: the same operations run in the four lanes of two SSE2
//! registers, so that the four latency chains of rotations overlap (docs/performance.md).
inline std::array<Svd<3>, kSvdLanes> svd3(const std::array<const Mat<3>*, kSvdLanes>& F) {
  std::array<int, kSvdLanes> exponents{};
  detail::Mat3<detail::Lanes> A, U, V, R;
  for (int lane = 0; lane < kSvdLanes; ++lane) {
    const Mat<3> scaled = F[lane] ? detail::scaled_to_unit(*F[lane], exponents[lane]) : Mat<3>::Zero();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) A(i, j).set(lane, scaled(i, j));
  }
  detail::svd3_factors(A, U, V, R);
  std::array<Svd<3>, kSvdLanes> result;
  for (int lane = 0; lane < kSvdLanes; ++lane) {
    if (!F[lane]) continue;  // unused: left as constructed
    Mat<3> u, v, r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        u(i, j) = U(i, j).get(lane);
        v(i, j) = V(i, j).get(lane);
        r(i, j) = R(i, j).get(lane);
      }
    result[lane] = detail::svd3_finish(u, v, r, exponents[lane]);
  }
  return result;
}

//! visit(i, svd(F(i))) for each i in [begin, end) with keep(i), in increasing i; keep is called
//! once per index, in increasing i. In 3D the SVDs are taken four at a time (the svd3 of four
//! matrices) before their four visits, so `visit` may change F(i). The results do not depend on
//! how the indices fall into groups.
template <int dim, class Matrix, class Keep, class Visit>
void for_each_svd(std::size_t begin, std::size_t end, Matrix&& F, Keep&& keep, Visit&& visit) {
  if constexpr (dim == 2) {
    for (std::size_t i = begin; i != end; ++i)
      if (keep(i)) visit(i, svd2(F(i)));
  } else {
    std::array<std::size_t, kSvdLanes> index{};
    std::array<const Mat<3>*, kSvdLanes> matrix{};
    int filled = 0;
    const auto flush = [&] {
      const std::array<Svd<3>, kSvdLanes> f = svd3(matrix);
      for (int lane = 0; lane < filled; ++lane) visit(index[lane], f[lane]);
      matrix.fill(nullptr);
      filled = 0;
    };
    for (std::size_t i = begin; i != end; ++i) {
      if (!keep(i)) continue;
      index[filled] = i;
      matrix[filled] = &F(i);
      if (++filled == kSvdLanes) flush();
    }
    if (filled > 0) flush();
  }
}

template <int dim>
Svd<dim> svd(const Mat<dim>& F) {
  if constexpr (dim == 2) {
    return svd2(F);
  } else {
    return svd3(F);
  }
}

//! A diag(d) B^T (F = U diag(sigma) V^T, tau = U diag(tau_i) U^T) as one scaled copy and one
//! product: Eigen's nested lazy product evaluated A diag(d) again for every coefficient, one
//! call per coefficient (docs/performance.md: the same sums up to their rounding order).
template <int dim>
Mat<dim> scaled_product(const Mat<dim>& A, const Vec<dim>& d, const Mat<dim>& B) {
  const Mat<dim> scaled = A * d.asDiagonal();
  return scaled * B.transpose();
}

template <int dim>
Polar<dim> polar(const Mat<dim>& F) {
  const Svd<dim> f = svd(F);
  return {f.U * f.V.transpose(), f.V * f.sigma.asDiagonal() * f.V.transpose()};
}

}  // namespace mpm::math
