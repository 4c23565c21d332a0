// The 3x3 SVD (math::svd3, McAdams et al. 2011 with exact rotations) against its contract in
// math/svd.h and against Eigen's JacobiSVD: on random matrices, on random rotations times random
// diagonals (signs and magnitudes down to 1e-12 included) and on the degenerate cases one by one.
#include <doctest/doctest.h>

#include <mpm/math/svd.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace mpm;

namespace {

constexpr double kTolerance = 1e-12;

struct Sample {
  std::string name;
  Mat<3> F;
};

// Largest errors over all samples, printed once so that the margin to kTolerance is visible.
struct WorstErrors {
  double reconstruction = 0.0;   // ||U diag(sigma) V^T - F|| / ||F||
  double orthogonality = 0.0;    // max of ||U^T U - I||, ||V^T V - I||
  double singular_values = 0.0;  // max_i ||sigma_i| - sigma_i(Eigen)| / sigma_0
};

Mat<3> random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized().toRotationMatrix();
}

// ||M||_F without overflow at the 1e300 scale, where the squares in M.norm() would overflow.
double frobenius_norm(const Mat<3>& M) {
  const double largest = M.cwiseAbs().maxCoeff();
  return largest == 0.0 ? 0.0 : largest * (M / largest).norm();
}

// Checks the contract of math/svd.h on one F; the details of a failure are captured.
void check_svd(const Sample& sample, WorstErrors& worst) {
  const Mat<3>& F = sample.F;
  const math::Svd<3> f = math::svd3(F);
  const double norm = frobenius_norm(F);
  const double reconstruction = frobenius_norm(f.U * f.sigma.asDiagonal() * f.V.transpose() - F);
  const double orthogonality = std::max((f.U.transpose() * f.U - Mat<3>::Identity()).norm(),
                                        (f.V.transpose() * f.V - Mat<3>::Identity()).norm());
  const Vec<3> reference = Eigen::JacobiSVD<Mat<3>>(F).singularValues();
  const double singular_values = norm == 0.0 ? f.sigma.cwiseAbs().maxCoeff()
                                             : (f.sigma.cwiseAbs() - reference).cwiseAbs().maxCoeff() / reference(0);
  worst.reconstruction = std::max(worst.reconstruction, norm == 0.0 ? reconstruction : reconstruction / norm);
  worst.orthogonality = std::max(worst.orthogonality, orthogonality);
  worst.singular_values = std::max(worst.singular_values, singular_values);

  const bool fine = reconstruction <= (norm == 0.0 ? 1e-300 : kTolerance * norm) && orthogonality <= kTolerance &&
                    std::abs(f.U.determinant() - 1.0) <= kTolerance &&
                    std::abs(f.V.determinant() - 1.0) <= kTolerance && singular_values <= kTolerance;
  // Also: only sigma_2 may be negative.
  const bool ordered = f.sigma(0) >= f.sigma(1) && f.sigma(1) >= std::abs(f.sigma(2));
  // The sign of det F is only defined when det F is above its own round-off, about
  // eps ||F||^3; below, F is singular to working precision and either sign is right. F / ||F||
  // keeps det from overflowing or underflowing at the extreme scales.
  const double det = norm == 0.0 ? 0.0 : Mat<3>(F / norm).determinant();
  const bool sign_known = std::abs(det) > 1e-12;
  const bool signed_right = !sign_known || (f.sigma(2) < 0.0) == (det < 0.0);
  if (fine && ordered && signed_right) return;
  CAPTURE(sample.name);
  CAPTURE(F);
  CAPTURE(f.sigma.transpose());
  CAPTURE(reference.transpose());
  CAPTURE(reconstruction);
  CAPTURE(orthogonality);
  CAPTURE(singular_values);
  CHECK(fine);
  CHECK(ordered);
  CHECK(signed_right);
}

std::vector<Sample> degenerate_samples() {
  std::mt19937_64 rng(7);
  const Mat<3> Q = random_rotation(rng), P = random_rotation(rng);
  const auto rotated = [&](double a, double b, double c) {
    return Mat<3>(Q * Vec<3>(a, b, c).asDiagonal() * P.transpose());
  };
  Mat<3> rank_two_exact;  // third row = first + second, exact in binary
  rank_two_exact << 1, 2, 3, 0.5, -1, 4, 1.5, 1, 7;
  return {
      {"identity", Mat<3>::Identity()},
      {"minus identity", -Mat<3>::Identity()},
      {"zero", Mat<3>::Zero()},
      {"diag(2, 2, 1)", Vec<3>(2, 2, 1).asDiagonal()},
      {"diag(1, 2, 2)", Vec<3>(1, 2, 2).asDiagonal()},
      {"diag(3, 3, 3)", 3.0 * Mat<3>::Identity()},
      {"diag(1, -1, 1)", Vec<3>(1, -1, 1).asDiagonal()},
      {"rotated (2, 2, 1)", rotated(2, 2, 1)},
      {"rotated (3, 3, 3)", rotated(3, 3, 3)},
      {"rotated (1, 1, 2)", rotated(1, 1, 2)},
      {"rotated (2, 2, -1)", rotated(2, 2, -1)},
      {"rank two, diag(1, 2, 0)", Vec<3>(1, 2, 0).asDiagonal()},
      {"rank one, diag(0, 0, 5)", Vec<3>(0, 0, 5).asDiagonal()},
      {"rank two, rotated", rotated(3, 1, 0)},
      {"rank one, rotated", rotated(3, 0, 0)},
      {"rank two, dependent rows", rank_two_exact},
      {"rank one, outer product", Vec<3>(1, -2, 0.5) * Vec<3>(3, 1, -1).transpose()},
      {"one nonzero entry", (Mat<3>() << 0, 0, 0, 0, 0, 1e-3, 0, 0, 0).finished()},
      {"tiny, 1e-150", 1e-150 * rotated(3, 2, -1)},
      {"huge, 1e150", 1e150 * rotated(3, 2, -1)},
      {"subnormal", 1e-310 * Mat<3>::Identity()},
      {"near overflow, 1e300", 1e300 * rotated(1, 0.5, -0.25)},
      {"inverted", rotated(1.5, 1, -0.5)},
      {"reflection", Q * Vec<3>(-1, 1, 1).asDiagonal()},
      {"nearly singular", rotated(1, 1, 1e-10)},
      {"nearly singular, inverted", rotated(1, 1, -1e-10)},
      {"two small, (1, 1e-9, 1e-10)", rotated(1, 1e-9, 1e-10)},
      {"two small, (1, 1e-5, -1e-9)", rotated(1, 1e-5, -1e-9)},
      {"two small, equal (1, 1e-8, 1e-8)", rotated(1, 1e-8, 1e-8)},
      {"close values (1, 1 + 1e-9, 1 - 1e-9)", rotated(1, 1 + 1e-9, 1 - 1e-9)},
  };
}

}  // namespace

TEST_CASE("svd3: degenerate cases one by one") {
  WorstErrors worst;
  for (const Sample& sample : degenerate_samples()) {
    CAPTURE(sample.name);
    check_svd(sample, worst);
  }
  MESSAGE("degenerate cases, worst relative errors: reconstruction " << worst.reconstruction << ", orthogonality "
                                                                     << worst.orthogonality << ", singular values "
                                                                     << worst.singular_values);
}

TEST_CASE("svd3: random matrices and random rotations times random diagonals") {
  std::mt19937_64 rng(2011);
  std::uniform_real_distribution<double> entry(-2.0, 2.0), exponent(-12.0, 0.0), unit(0.0, 1.0);
  WorstErrors worst;
  constexpr int kCount = 10000;
  for (int n = 0; n < kCount; ++n) {
    const Mat<3> F = Mat<3>::NullaryExpr([&] { return entry(rng); });
    check_svd({"random entries in [-2, 2], #" + std::to_string(n), F}, worst);
  }
  for (int n = 0; n < kCount; ++n) {
    // Magnitudes log-uniform in [1e-12, 1] (half of them) or uniform in [0, 2], random signs.
    const bool log_uniform = n % 2 == 0;
    const Vec<3> diagonal = Vec<3>::NullaryExpr([&] {
      const double magnitude = log_uniform ? std::pow(10.0, exponent(rng)) : 2.0 * unit(rng);
      return unit(rng) < 0.5 ? -magnitude : magnitude;
    });
    const Mat<3> F = random_rotation(rng) * diagonal.asDiagonal() * random_rotation(rng).transpose();
    check_svd({"rotation diag rotation, #" + std::to_string(n), F}, worst);
  }
  MESSAGE("random cases, worst relative errors: reconstruction " << worst.reconstruction << ", orthogonality "
                                                                 << worst.orthogonality << ", singular values "
                                                                 << worst.singular_values);
}

TEST_CASE("svd<3> and polar<3> use svd3") {
  std::mt19937_64 rng(3);
  const Mat<3> F = random_rotation(rng) * Vec<3>(2.0, 0.5, -0.25).asDiagonal() * random_rotation(rng).transpose();
  const math::Svd<3> expected = math::svd3(F), f = math::svd<3>(F);
  CHECK(f.U == expected.U);
  CHECK(f.sigma == expected.sigma);
  CHECK(f.V == expected.V);
  const math::Polar<3> p = math::polar<3>(F);
  CHECK((p.R - expected.U * expected.V.transpose()).norm() == 0.0);
}

TEST_CASE("svd3: a NaN entry shows in the singular values") {
  Mat<3> F = Mat<3>::Identity();
  F(1, 2) = std::numeric_limits<double>::quiet_NaN();
  CHECK(math::svd3(F).sigma.hasNaN());
}
