// Every kernel: partition of unity, non-negativity, linear reproduction, C1 continuity (the
// weight and its derivative are continuous across cell faces, and dw matches finite
// differences of w), and the uGIMP -> quadratic B-spline identity of paper sec. 3.3.
#include <mpm/core/kernels.h>

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace mpm;

namespace {
std::vector<Kernel> all_kernels() { return {QuadraticBSpline{}, CubicBSpline{}, UGimp{0.5}, UGimp{0.25}, UGimp{0.1}}; }

// Weight and derivative of node `node` at coordinate xi (0 outside the stencil).
void weight_of_node(const Kernel& kernel, double xi, int node, double& w, double& dw) {
  std::visit(
      [&](const auto& k) {
        int base;
        double ws[4], dws[4];
        k(xi, base, ws, dws);
        const int i = node - base;
        w = (i >= 0 && i < k.support) ? ws[i] : 0.0;
        dw = (i >= 0 && i < k.support) ? dws[i] : 0.0;
      },
      kernel);
}
}  // namespace

TEST_CASE("kernels: partition of unity, non-negativity and linear reproduction") {
  for (const Kernel& kernel : all_kernels()) {
    CAPTURE(kernel_name(kernel));
    for (double xi = 3.0; xi < 5.0; xi += 0.01237) {
      std::visit(
          [&](const auto& k) {
            int base;
            double w[4], dw[4];
            k(xi, base, w, dw);
            double sum = 0.0, first = 0.0, dsum = 0.0, dfirst = 0.0;
            for (int i = 0; i < k.support; ++i) {
              CHECK(w[i] >= -1e-15);
              sum += w[i];
              first += w[i] * (base + i - xi);
              dsum += dw[i];
              dfirst += dw[i] * (base + i);
            }
            CHECK(sum == doctest::Approx(1.0).epsilon(1e-14));
            CHECK(std::fabs(first) < 1e-13);
            CHECK(std::fabs(dsum) < 1e-13);                        // d/dxi of sum w = 0
            CHECK(dfirst == doctest::Approx(1.0).epsilon(1e-13));  // d/dxi of sum w x_i = 1
          },
          kernel);
    }
  }
}

TEST_CASE("kernels: C1 continuity and derivative against finite differences") {
  const double h = 1e-6;
  for (const Kernel& kernel : all_kernels()) {
    CAPTURE(kernel_name(kernel));
    for (int node = 3; node <= 5; ++node) {
      // Sample densely, including exactly at cell faces and half-cells where stencils switch.
      for (double xi = 1.0; xi <= 8.0; xi += 0.03125) {
        double wm, dwm, wp, dwp, w, dw;
        weight_of_node(kernel, xi - h, node, wm, dwm);
        weight_of_node(kernel, xi + h, node, wp, dwp);
        weight_of_node(kernel, xi, node, w, dw);
        CHECK(std::fabs(wp - wm) < 4.0 * h);  // w continuous
        CHECK(std::fabs(dwp - dwm) < 1e-4);   // dw continuous (C1)
        CHECK((wp - wm) / (2 * h) == doctest::Approx(dw).epsilon(1e-5).scale(1.0));
      }
    }
  }
}

TEST_CASE("kernels: uGIMP with particle size dx is the quadratic B-spline (paper sec. 3.3)") {
  for (double xi = 2.0; xi < 3.0; xi += 0.0173) {
    int b1, b2;
    double w1[4], dw1[4], w2[4], dw2[4];
    QuadraticBSpline{}(xi, b1, w1, dw1);
    UGimp{0.5}(xi, b2, w2, dw2);
    REQUIRE(b1 == b2);
    for (int i = 0; i < 3; ++i) {
      CHECK(w1[i] == doctest::Approx(w2[i]).epsilon(1e-14));
      CHECK(dw1[i] == doctest::Approx(dw2[i]).epsilon(1e-14));
    }
  }
}

TEST_CASE("kernels: uGIMP's closed form is the hat convolved with the particle's box") {
  // The definition (paper eq. 5-6): w(r) = (H(r + h) - H(r - h)) / (2h), dw/dr = (N1(r + h) -
  // N1(r - h)) / (2h), H the antiderivative of the hat N1, written out piece by piece.
  const auto N1 = [](double r) { return std::fabs(r) < 1.0 ? 1.0 - std::fabs(r) : 0.0; };
  const auto H = [](double s) {
    if (s <= -1.0) return 0.0;
    if (s <= 0.0) return 0.5 * (1.0 + s) * (1.0 + s);
    if (s <= 1.0) return 1.0 - 0.5 * (1.0 - s) * (1.0 - s);
    return 1.0;
  };
  for (const double h : {0.5, 0.3, 0.25, 0.1, 0.01}) {
    CAPTURE(h);
    for (double xi = 2.0; xi < 4.0; xi += 0.00731) {
      int base;
      double w[3], dw[3];
      UGimp{h}(xi, base, w, dw);
      for (int i = 0; i < 3; ++i) {
        const double r = xi - (base + i);
        CHECK(w[i] == doctest::Approx((H(r + h) - H(r - h)) / (2 * h)).epsilon(1e-14).scale(1.0));
        CHECK(dw[i] == doctest::Approx((N1(r + h) - N1(r - h)) / (2 * h)).epsilon(1e-13).scale(1.0));
      }
    }
  }
}
