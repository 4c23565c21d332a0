#pragma once
//! The 3x3 algebra of the CUDA back-end, in the particle's precision T (float or double): the
//! rotation-variant SVD, the principal stresses of the hyperelastic models and the Hencky return
//! maps. Each function follows its CPU counterpart operation for operation (math/svd.h,
//! constitutive/*.h, plasticity/drucker_prager.h and von_mises.h), so that a double-precision
//! step agrees with the CPU step to round-off (tests/gpu/test_cuda_step.cpp); the CPU headers
//! are Eigen code for the host and are not compiled for the device. Internal.
#include "device_solid.h"

#include <cuda_runtime.h>

#include <cmath>

namespace mpm::cuda::detail {

#define MPM_HD __host__ __device__ __forceinline__
// The algebra also compiles for the host (tests/gpu/test_device_math.cpp), where GCC has no unroll pragma.
#if defined(__CUDACC__)
#define MPM_UNROLL _Pragma("unroll")
#else
#define MPM_UNROLL
#endif

template <class T>
struct Limits;
template <>
struct Limits<double> {
  static constexpr double epsilon = 2.220446049250313e-16;
  static constexpr double tiny = 1e-150;  //!< an off-diagonal entry of the scaled S below this is dropped
};
template <>
struct Limits<float> {
  static constexpr float epsilon = 1.1920929e-7f;
  static constexpr float tiny = 1e-30f;
};

template <class T>
struct V3 {
  T a[3];
  MPM_HD T& operator[](int i) { return a[i]; }
  MPM_HD const T& operator[](int i) const { return a[i]; }
};

//! Row-major 3x3: m[r][c].
template <class T>
struct M3 {
  T m[3][3];
  MPM_HD T& operator()(int r, int c) { return m[r][c]; }
  MPM_HD const T& operator()(int r, int c) const { return m[r][c]; }
  MPM_HD static M3 identity() {
    M3 I{};
    I(0, 0) = I(1, 1) = I(2, 2) = T(1);
    return I;
  }
};

template <class T>
MPM_HD M3<T> multiply(const M3<T>& A, const M3<T>& B) {
  M3<T> C;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) MPM_UNROLL
  for (int j = 0; j < 3; ++j) C(i, j) = A(i, 0) * B(0, j) + A(i, 1) * B(1, j) + A(i, 2) * B(2, j);
  return C;
}

template <class T>
MPM_HD M3<T> transposed(const M3<T>& A) {
  M3<T> At;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) MPM_UNROLL
  for (int j = 0; j < 3; ++j) At(i, j) = A(j, i);
  return At;
}

//! U diag(s) V^T
template <class T>
MPM_HD M3<T> compose(const M3<T>& U, const V3<T>& s, const M3<T>& V) {
  M3<T> C;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) MPM_UNROLL
  for (int j = 0; j < 3; ++j) C(i, j) = U(i, 0) * s[0] * V(j, 0) + U(i, 1) * s[1] * V(j, 1) + U(i, 2) * s[2] * V(j, 2);
  return C;
}

template <class T>
MPM_HD void swap_values(T& a, T& b) {
  const T t = a;
  a = b;
  b = t;
}

template <class T>
MPM_HD void swap_columns(M3<T>& A, int a, int b) {
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) swap_values(A(i, a), A(i, b));
}

template <class T>
MPM_HD void negate_column(M3<T>& A, int a) {
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) A(i, a) = -A(i, a);
}

template <class T>
struct Svd3 {
  M3<T> U;
  V3<T> sigma;
  M3<T> V;
};

//! math::svd2 of [a00 a01; a10 a11]: U, sigma, V as 2x2 (row-major).
template <class T>
MPM_HD void svd2(T a00, T a01, T a10, T a11, T (&U)[2][2], T (&sigma)[2], T (&V)[2][2]) {
  const T theta = atan2(a10 - a01, a00 + a11);
  const T c = cos(theta), s = sin(theta);
  const T s00 = c * a00 + s * a10, s11 = -s * a01 + c * a11;
  const T s01 = c * a01 + s * a11;
  const T phi = T(0.5) * atan2(T(2) * s01, s00 - s11);
  const T cp = cos(phi), sp = sin(phi);
  const T mean = T(0.5) * (s00 + s11), radius = hypot(T(0.5) * (s00 - s11), s01);
  V[0][0] = cp;
  V[0][1] = -sp;
  V[1][0] = sp;
  V[1][1] = cp;
  sigma[0] = mean + radius;
  sigma[1] = mean - radius;
  // U = R V with R = [c -s; s c]
  U[0][0] = c * cp - s * sp;
  U[0][1] = -c * sp - s * cp;
  U[1][0] = s * cp + c * sp;
  U[1][1] = -s * sp + c * cp;
}

//! math::detail::jacobi_rotate
template <class T>
MPM_HD void jacobi_rotate(M3<T>& S, M3<T>& V, int p, int q) {
  const int r = 3 - p - q;
  const T spq = S(p, q), d = S(q, q) - S(p, p);
  T t = 0, c = 1, s = 0;
  if (spq * spq < T(0.5) * Limits<T>::epsilon * d * d) {
    t = spq / d;
    s = t;
  } else if (fabs(spq) > Limits<T>::tiny) {
    const T radius = sqrt(d * d + T(4) * spq * spq);
    const T twice_spq = copysign(T(2), d) * spq;
    const T sum = fabs(d) + radius;
    const T inverse_norm = T(1) / sqrt(T(2) * radius * sum);
    t = twice_spq / sum;
    c = sum * inverse_norm;
    s = twice_spq * inverse_norm;
  }
  S(p, p) -= t * spq;
  S(q, q) += t * spq;
  S(p, q) = S(q, p) = 0;
  const T srp = S(r, p), srq = S(r, q);
  S(r, p) = S(p, r) = c * srp - s * srq;
  S(r, q) = S(q, r) = s * srp + c * srq;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) {
    const T vp = V(i, p), vq = V(i, q);
    V(i, p) = c * vp - s * vq;
    V(i, q) = s * vp + c * vq;
  }
}

//! math::detail::givens_eliminate
template <class T>
MPM_HD void givens_eliminate(M3<T>& R, M3<T>& U, int p, int q, int column) {
  const T a = R(p, column), b = R(q, column);
  const T r = sqrt(a * a + b * b), inverse_r = T(1) / r;
  const T c = r > 0 ? a * inverse_r : T(1), s = r > 0 ? b * inverse_r : T(0);
  for (int j = column; j < 3; ++j) {
    const T rp = R(p, j), rq = R(q, j);
    R(p, j) = c * rp + s * rq;
    R(q, j) = -s * rp + c * rq;
  }
  R(q, column) = 0;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) {
    const T up = U(i, p), uq = U(i, q);
    U(i, p) = c * up + s * uq;
    U(i, q) = -s * up + c * uq;
  }
}

template <class T>
MPM_HD void order_first(Svd3<T>& f) {
  if (f.sigma[0] >= f.sigma[1]) return;
  swap_values(f.sigma[0], f.sigma[1]);
  swap_columns(f.U, 0, 1);
  swap_columns(f.V, 0, 1);
  negate_column(f.U, 1);
  negate_column(f.V, 1);
}

template <class T>
MPM_HD void order_last(Svd3<T>& f) {
  if (f.sigma[1] >= fabs(f.sigma[2])) return;
  const T sign = f.sigma[2] < 0 ? T(-1) : T(1);
  const T larger = fabs(f.sigma[2]), smaller = sign * f.sigma[1];
  f.sigma[1] = larger;
  f.sigma[2] = smaller;
  swap_columns(f.U, 1, 2);
  swap_columns(f.V, 1, 2);
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) {
    f.U(i, 1) *= sign;
    f.U(i, 2) *= -sign;
    f.V(i, 2) = -f.V(i, 2);
  }
}

//! math::svd3 (McAdams et al. 2011 with exact rotations and sweeps to round-off): U and V
//! proper rotations, |sigma_0| >= |sigma_1| >= |sigma_2|, the sign of det F on sigma_2.
template <class T>
MPM_HD Svd3<T> svd3(const M3<T>& F) {
  Svd3<T> f{M3<T>::identity(), {T(0), T(0), T(0)}, M3<T>::identity()};
  T largest = 0;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) MPM_UNROLL
  for (int j = 0; j < 3; ++j) largest = fmax(largest, fabs(F(i, j)));
  if (largest == 0) return f;
  int exponent = 0;
  frexp(largest, &exponent);
  const T scale = ldexp(T(1), -exponent / 2) * ldexp(T(1), exponent / 2 - exponent);
  M3<T> A;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) MPM_UNROLL
  for (int j = 0; j < 3; ++j) A(i, j) = F(i, j) * scale;

  M3<T> S = multiply(transposed(A), A);
  const T squared_tolerance = Limits<T>::epsilon * Limits<T>::epsilon;
  for (int sweep = 0; sweep < 12; ++sweep) {
    const T off = S(0, 1) * S(0, 1) + S(0, 2) * S(0, 2) + S(1, 2) * S(1, 2);
    if (off <= squared_tolerance * (S(0, 0) * S(0, 0) + S(1, 1) * S(1, 1) + S(2, 2) * S(2, 2))) break;
    jacobi_rotate(S, f.V, 0, 1);
    jacobi_rotate(S, f.V, 0, 2);
    jacobi_rotate(S, f.V, 1, 2);
  }

  M3<T> R = multiply(A, f.V);
  T norms[3];
  MPM_UNROLL
  for (int j = 0; j < 3; ++j) norms[j] = R(0, j) * R(0, j) + R(1, j) * R(1, j) + R(2, j) * R(2, j);
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  MPM_UNROLL
  for (int k = 0; k < 3; ++k) {
    const int a = pairs[k][0], b = pairs[k][1];
    if (norms[a] >= norms[b]) continue;
    swap_columns(R, a, b);
    swap_columns(f.V, a, b);
    negate_column(R, b);
    negate_column(f.V, b);
    swap_values(norms[a], norms[b]);
  }

  givens_eliminate(R, f.U, 0, 1, 0);
  givens_eliminate(R, f.U, 0, 2, 0);
  givens_eliminate(R, f.U, 1, 2, 1);
  f.sigma = {R(0, 0), R(1, 1), R(2, 2)};

  if (fabs(R(1, 2)) > T(4) * Limits<T>::epsilon * R(0, 0)) {
    T bu[2][2], bs[2], bv[2][2];
    svd2(R(1, 1), R(1, 2), R(2, 1), R(2, 2), bu, bs, bv);
    MPM_UNROLL
    for (int i = 0; i < 3; ++i) {
      const T u1 = f.U(i, 1), u2 = f.U(i, 2), v1 = f.V(i, 1), v2 = f.V(i, 2);
      f.U(i, 1) = u1 * bu[0][0] + u2 * bu[1][0];
      f.U(i, 2) = u1 * bu[0][1] + u2 * bu[1][1];
      f.V(i, 1) = v1 * bv[0][0] + v2 * bv[1][0];
      f.V(i, 2) = v1 * bv[0][1] + v2 * bv[1][1];
    }
    f.sigma[1] = bs[0];
    f.sigma[2] = bs[1];
  }

  order_first(f);
  order_last(f);
  order_first(f);
  const T back = ldexp(T(1), exponent - exponent / 2) * ldexp(T(1), exponent / 2);
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) f.sigma[i] *= back;
  return f;
}

// ---- Elasticity in principal space (constitutive/detail/isotropic.h and the models) ----

template <class T>
struct ExtendedLog {
  T value, first;
  MPM_HD explicit ExtendedLog(T x) {
    constexpr T c = T(0.1);  // constitutive::inversion_clamp
    if (x >= c) {
      value = log(x);
      first = T(1) / x;
    } else {
      const T d = (x - c) / c;
      value = log(c) + d - T(0.5) * d * d;
      first = (T(1) - d) / c;
    }
  }
};

template <class T>
MPM_HD T safe_denominator(T x) {
  return fabs(x) >= T(1e-6) ? x : copysign(T(1e-6), x);
}

//! p_i = d psihat / d sigma_i of the material's elasticity.
template <class T>
MPM_HD V3<T> principal_stress(const DeviceMaterial& m, const V3<T>& s) {
  const T mu = T(m.mu), lambda = T(m.lambda);
  V3<T> p;
  if (m.elasticity == Elasticity::fixed_corotated) {
    const T J = s[0] * s[1] * s[2];
    const T dJ[3] = {s[1] * s[2], s[2] * s[0], s[0] * s[1]};
    MPM_UNROLL
    for (int i = 0; i < 3; ++i) p[i] = T(2) * mu * (s[i] - T(1)) + lambda * (J - T(1)) * dJ[i];
    return p;
  }
  const ExtendedLog<T> L[3] = {ExtendedLog<T>(s[0]), ExtendedLog<T>(s[1]), ExtendedLog<T>(s[2])};
  const T trace = L[0].value + L[1].value + L[2].value;
  if (m.elasticity == Elasticity::neo_hookean) {
    MPM_UNROLL
    for (int i = 0; i < 3; ++i) p[i] = mu * s[i] + (lambda * trace - mu) * L[i].first;
    return p;
  }
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) p[i] = (T(2) * mu * L[i].value + lambda * trace) * L[i].first;
  return p;
}

//! Kirchhoff stress tau = U diag(p_i sigma_i) U^T as its 6 symmetric entries (xx, yy, zz, xy, xz, yz).
template <class T>
MPM_HD void kirchhoff(const DeviceMaterial& m, const Svd3<T>& f, T (&tau)[6]) {
  const V3<T> p = principal_stress(m, f.sigma);
  const T d[3] = {p[0] * f.sigma[0], p[1] * f.sigma[1], p[2] * f.sigma[2]};
  const auto entry = [&](int i, int j) {
    return f.U(i, 0) * d[0] * f.U(j, 0) + f.U(i, 1) * d[1] * f.U(j, 1) + f.U(i, 2) * d[2] * f.U(j, 2);
  };
  tau[0] = entry(0, 0);
  tau[1] = entry(1, 1);
  tau[2] = entry(2, 2);
  tau[3] = entry(0, 1);
  tau[4] = entry(0, 2);
  tau[5] = entry(1, 2);
}

//! The Hencky return maps (plasticity/drucker_prager.h without dilatancy or rate dependence,
//! plasticity/von_mises.h): projects F^E and updates `plastic`; f receives the SVD of the F^E
//! left. Elastic materials keep F^E and f is its SVD.
template <class T>
MPM_HD void return_map(const DeviceMaterial& m, M3<T>& Fe, T& plastic, Svd3<T>& f) {
  f = svd3(Fe);
  if (m.plasticity == Plasticity::none) return;
  const T mu = T(m.mu), lambda = T(m.lambda);
  V3<T> eps;
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) eps[i] = log(fabs(safe_denominator(f.sigma[i])));
  V3<T> H;
  if (m.plasticity == Plasticity::von_mises) {
    const T mean = (eps[0] + eps[1] + eps[2]) / T(3);
    const V3<T> dev = {eps[0] - mean, eps[1] - mean, eps[2] - mean};
    const T dev_norm = sqrt(dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]);
    const T y = sqrt(T(1.5)) * T(2) * mu * dev_norm - T(m.yield_stress);
    if (y <= 0) return;
    const T share = y / (sqrt(T(1.5)) * T(2) * mu * dev_norm);
    MPM_UNROLL
    for (int i = 0; i < 3; ++i) H[i] = eps[i] - share * dev[i];
  } else {
    const T alpha = T(m.alpha), k = T(m.k);
    MPM_UNROLL
    for (int i = 0; i < 3; ++i) eps[i] += plastic / T(3);
    const T trace = eps[0] + eps[1] + eps[2];
    const T bulk = T(3) * lambda + T(2) * mu;
    H = eps;
    if (alpha > 0 && alpha * bulk * trace >= k) {  // II: to the apex
      const T apex_trace = k / (alpha * bulk);
      H = {apex_trace / T(3), apex_trace / T(3), apex_trace / T(3)};
      plastic = fmax(trace - apex_trace, T(0));
    } else {
      const T mean = trace / T(3);
      const V3<T> dev = {eps[0] - mean, eps[1] - mean, eps[2] - mean};
      // y = ||dev tau|| + alpha tr tau - k with dev tau = 2 mu dev eps, tr tau = bulk tr eps
      const T tau_dev_norm = T(2) * mu * sqrt(dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]);
      const T tau_trace = T(3) * (T(2) * mu * mean + lambda * trace);
      const T y = tau_dev_norm + alpha * tau_trace - k;
      if (y <= 0 && plastic == 0) return;  // I
      plastic = 0;
      if (y > 0) {  // III
        const T dev_norm = sqrt(dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]);
        const T slope = T(2) * mu;
        const T share = slope > 0 && y < slope * dev_norm ? y / (slope * dev_norm) : T(1);
        MPM_UNROLL
        for (int i = 0; i < 3; ++i) H[i] -= share * dev[i];
      }
    }
  }
  MPM_UNROLL
  for (int i = 0; i < 3; ++i) f.sigma[i] = exp(H[i]);
  Fe = compose(f.U, f.sigma, f.V);
}

}  // namespace mpm::cuda::detail
