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

// Random entries in [-2, 2], then rotation diag rotation with magnitudes log-uniform in
// [1e-12, 1] (half of them) or uniform in [0, 2] and random signs; `count` of each.
std::vector<Sample> random_samples(int count) {
  std::mt19937_64 rng(2011);
  std::uniform_real_distribution<double> entry(-2.0, 2.0), exponent(-12.0, 0.0), unit(0.0, 1.0);
  std::vector<Sample> samples;
  for (int n = 0; n < count; ++n)
    samples.push_back(
        {"random entries in [-2, 2], #" + std::to_string(n), Mat<3>::NullaryExpr([&] { return entry(rng); })});
  for (int n = 0; n < count; ++n) {
    const bool log_uniform = n % 2 == 0;
    const Vec<3> diagonal = Vec<3>::NullaryExpr([&] {
      const double magnitude = log_uniform ? std::pow(10.0, exponent(rng)) : 2.0 * unit(rng);
      return unit(rng) < 0.5 ? -magnitude : magnitude;
    });
    samples.push_back({"rotation diag rotation, #" + std::to_string(n),
                       random_rotation(rng) * diagonal.asDiagonal() * random_rotation(rng).transpose()});
  }
  return samples;
}

TEST_CASE("svd3: random matrices and random rotations times random diagonals") {
  WorstErrors worst;
  for (const Sample& sample : random_samples(10000)) check_svd(sample, worst);
  MESSAGE("random cases, worst relative errors: reconstruction " << worst.reconstruction << ", orthogonality "
                                                                 << worst.orthogonality << ", singular values "
                                                                 << worst.singular_values);
}

// The svd3 of four matrices runs svd3's operations in four lanes: each lane must give svd3 of
// its matrix bit for bit (where the compiler fuses multiply-adds, it may fuse them differently
// in the two forms: then to round-off), wherever the matrix falls among the lanes and whatever
// its neighbours are (a NaN or a zero matrix next to it included).
TEST_CASE("svd3 of four matrices: each lane is svd3 of its own matrix") {
#if defined(__FMA__)
  constexpr double kLaneTolerance = 1e-14;
#else
  constexpr double kLaneTolerance = 0.0;
#endif
  std::vector<Sample> samples = degenerate_samples();
  for (Sample& sample : random_samples(2000)) samples.push_back(std::move(sample));
  Mat<3> nan_matrix = Mat<3>::Identity();
  nan_matrix(0, 1) = std::numeric_limits<double>::quiet_NaN();
  samples.insert(samples.begin() + 3, {"NaN entry", nan_matrix});
  for (int skip = 2; skip <= 7; ++skip) {  // every skip-th sample left out: lanes shift
    CAPTURE(skip);
    std::vector<bool> visited(samples.size(), false);
    double worst = 0.0;
    math::for_each_svd<3>(
        0, samples.size(), [&](std::size_t i) -> const Mat<3>& { return samples[i].F; },
        [&](std::size_t i) { return i % skip != 1; },
        [&](std::size_t i, const math::Svd<3>& f) {
          visited[i] = true;
          const math::Svd<3> expected = math::svd3(samples[i].F);
          if (std::isnan(samples[i].F(0, 1))) {
            CHECK(f.sigma.hasNaN());
            return;
          }
          const double difference =
              std::max({(f.U - expected.U).cwiseAbs().maxCoeff(), (f.V - expected.V).cwiseAbs().maxCoeff(),
                        ((f.sigma - expected.sigma).cwiseAbs() / std::max(expected.sigma.cwiseAbs().maxCoeff(), 1e-300))
                            .maxCoeff()});
          if (difference > kLaneTolerance) {
            CAPTURE(samples[i].name);
            CHECK(difference <= kLaneTolerance);
          }
          worst = std::max(worst, difference);
        });
    for (std::size_t i = 0; i < samples.size(); ++i) CHECK(visited[i] == (i % skip != 1));
    CHECK(worst <= kLaneTolerance);
  }
}

TEST_CASE("for_each_svd in 2D is svd2 of each kept matrix, in order") {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> entry(-2.0, 2.0);
  std::vector<Mat<2>> matrices(9);
  for (Mat<2>& F : matrices) F = Mat<2>::NullaryExpr([&] { return entry(rng); });
  std::vector<std::size_t> order;
  math::for_each_svd<2>(
      1, matrices.size(), [&](std::size_t i) -> const Mat<2>& { return matrices[i]; },
      [](std::size_t i) { return i != 4; },
      [&](std::size_t i, const math::Svd<2>& f) {
        order.push_back(i);
        const math::Svd<2> expected = math::svd2(matrices[i]);
        CHECK(f.U == expected.U);
        CHECK(f.sigma == expected.sigma);
        CHECK(f.V == expected.V);
      });
  CHECK(order == std::vector<std::size_t>{1, 2, 3, 5, 6, 7, 8});
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

TEST_CASE_TEMPLATE("scaled_product is A diag(d) B^T to round-off", Matrix, Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  std::srand(5);
  for (int n = 0; n < 100; ++n) {
    const Mat<dim> A = Mat<dim>::Random(), B = Mat<dim>::Random();
    const Vec<dim> d = 10.0 * Vec<dim>::Random();
    Mat<dim> expected = Mat<dim>::Zero();  // sum_k A_ik d_k B_jk, one term at a time
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j)
        for (int k = 0; k < dim; ++k) expected(i, j) += A(i, k) * d(k) * B(j, k);
    CHECK((math::scaled_product<dim>(A, d, B) - expected).cwiseAbs().maxCoeff() <= 1e-14 * 10.0 * dim);
  }
}
