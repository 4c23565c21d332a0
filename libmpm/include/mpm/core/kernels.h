#pragma once
//! Interpolation weights w_ip = prod_a N(r_a), r_a = (x_p - x_i)_a / dx (tensor products of 1D
//! kernels). Each kernel maps a particle coordinate in cell units, xi = (x_p - origin)/dx, to
//! the first stencil node `base` and the 1D weights and derivatives dN/dr of its `support`
//! nodes base, base+1, ... All satisfy partition of unity, non-negativity, linear
//! reproduction sum_i N_i (i - xi) = 0, and C1 continuity (tests/unit/mpm/core/test_kernels.cpp).
#include <cmath>
#include <string>
#include <variant>

namespace mpm {

//! Quadratic B-spline N2 (support 3). Identical to uGIMP with particle size dx (paper sec. 3.3).
struct QuadraticBSpline {
  static constexpr int support = 3;
  static const char* name() { return "quadratic"; }
  void operator()(double xi, int& base, double* w, double* dw) const {
    base = static_cast<int>(std::floor(xi - 0.5));
    const double f = xi - base;  // in [0.5, 1.5): distance to the first node
    const double a = 1.5 - f, b = f - 1.0, c = f - 0.5;
    w[0] = 0.5 * a * a;
    w[1] = 0.75 - b * b;
    w[2] = 0.5 * c * c;
    dw[0] = -a;
    dw[1] = -2.0 * b;
    dw[2] = c;
  }
};

//! Cubic B-spline N3 (support 4).
struct CubicBSpline {
  static constexpr int support = 4;
  static const char* name() { return "cubic"; }
  void operator()(double xi, int& base, double* w, double* dw) const {
    base = static_cast<int>(std::floor(xi)) - 1;
    const double t = xi - base - 1.0;  // in [0, 1): offset from node base+1
    const double s = 1.0 - t;
    w[0] = s * s * s / 6.0;
    w[1] = 0.5 * t * t * t - t * t + 2.0 / 3.0;
    w[2] = 0.5 * s * s * s - s * s + 2.0 / 3.0;
    w[3] = t * t * t / 6.0;
    dw[0] = -0.5 * s * s;
    dw[1] = 1.5 * t * t - 2.0 * t;
    dw[2] = -(1.5 * s * s - 2.0 * s);
    dw[3] = 0.5 * t * t;
  }
};

//! uGIMP (paper eq. 5-6): the linear hat N1 averaged over an axis-aligned particle box of side
//! L_p = 2 h dx, with 0 < h <= 1/2 so the support stays within 3 nodes:
//!   w(r) = (H(r + h) - H(r - h)) / (2h),  dw/dr = (N1(r + h) - N1(r - h)) / (2h),
//! where H is the antiderivative of N1. With h = 1/2 this is the quadratic B-spline.
struct UGimp {
  static constexpr int support = 3;
  double h = 0.5;  //!< particle half-size in cells, (0, 0.5]
  static const char* name() { return "ugimp"; }

  static double hat(double r) {  // max(0, 1 - |r|), 0 for NaN as std::fmax, but inlined (no libm call)
    const double t = 1.0 - std::fabs(r);
    return t > 0.0 ? t : 0.0;
  }
  //! H(s) = int_{-inf}^{s} N1: 0.5 (1 + s)^2 on [-1, 0], 1 - 0.5 (1 - s)^2 on [0, 1], i.e.
  //! 1/2 + c - c |c| / 2 with c = s clamped to [-1, 1]: no branch on the data (the transfer
  //! loops evaluate it six times per axis of every particle).
  static double hat_integral(double s) {
    const double lo = s > -1.0 ? s : -1.0, c = lo < 1.0 ? lo : 1.0;
    return 0.5 + c - 0.5 * c * std::fabs(c);
  }
  //! The three weights in closed form. An outer node at distance d in [1/2, 3/2] has, with
  //! t = 1 + h - d and t' = t clamped to [0, 2h], w = t'^2 / (4h) + max(t - 2h, 0) (1 - d
  //! where its box lies inside the hat's slope, the quadratic where it covers the hat's foot, 0
  //! beyond) and dw/dd = -t' / (2h); the middle node takes the rest (the weights sum to one).
  void operator()(double xi, int& base, double* w, double* dw) const {
    base = static_cast<int>(std::floor(xi - 0.5));
    const double fx = xi - base, inv = 0.25 / h, two_h = 2.0 * h;
    const auto outer = [&](double d, double& weight, double& slope) {
      const double t = 1.0 + h - d, low = t > 0.0 ? t : 0.0, clamped = low < two_h ? low : two_h;
      weight = clamped * clamped * inv + (t > two_h ? t - two_h : 0.0);
      slope = clamped * 2.0 * inv;  // -dw/dd
    };
    double s0, s2;
    outer(fx, w[0], s0);
    outer(2.0 - fx, w[2], s2);
    dw[0] = -s0;
    dw[2] = s2;
    w[1] = 1.0 - w[0] - w[2];
    dw[1] = s0 - s2;
  }
};

using Kernel = std::variant<QuadraticBSpline, CubicBSpline, UGimp>;

inline int kernel_support(const Kernel& k) {
  return std::visit([](const auto& kernel) { return kernel.support; }, k);
}

//! Thickness of the wall layer a domain needs so that no stencil leaves the grid: the nodes
//! within (support - 1) dx of a face carry the wall condition [m].
inline double wall_layer(const Kernel& k, double dx) { return (kernel_support(k) - 1) * dx; }

inline std::string kernel_name(const Kernel& k) {
  return std::visit([](const auto& kernel) { return std::string(kernel.name()); }, k);
}

}  // namespace mpm
