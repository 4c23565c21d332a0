// The core solve layer (mpm/core/solve): conjugate gradients against a direct solve, on scalar
// and vector unknowns, with the identity and Jacobi preconditioners; singular consistent
// systems; and the failures it must report (iteration cap, breakdown on an indefinite matrix).
#include <mpm/core/solve/conjugate_gradient.h>
#include <mpm/core/solve/preconditioners.h>

#include <doctest/doctest.h>
#include <tbb/task_arena.h>
#include <Eigen/Dense>

#include <cmath>
#include <random>
#include <vector>

namespace {

using mpm::solve::conjugate_gradient;
using mpm::solve::IdentityPreconditioner;
using mpm::solve::JacobiPreconditioner;
using mpm::solve::SolveControl;

//! A dense symmetric matrix as a linear map on std::vector<double>.
struct DenseMap {
  Eigen::MatrixXd A;
  int products = 0;
  void apply(const std::vector<double>& x, std::vector<double>& y) {
    ++products;
    y.resize(x.size());
    Eigen::Map<Eigen::VectorXd>(y.data(), long(y.size())) =
        A * Eigen::Map<const Eigen::VectorXd>(x.data(), long(x.size()));
  }
};

//! A random SPD matrix with a diagonal that spans `spread` orders of magnitude.
Eigen::MatrixXd random_spd(int n, double spread, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd B(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) B(i, j) = u(rng);
  Eigen::MatrixXd A = B * B.transpose() + n * Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd s(n);
  for (int i = 0; i < n; ++i) s[i] = std::pow(10.0, spread * i / (n - 1));
  return s.asDiagonal() * A * s.asDiagonal();
}

std::vector<double> random_vector(int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(n);
  for (double& x : v) x = u(rng);
  return v;
}

double max_error(const std::vector<double>& x, const Eigen::VectorXd& exact) {
  double e = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) e = std::max(e, std::fabs(x[i] - exact[long(i)]));
  return e / exact.cwiseAbs().maxCoeff();
}

}  // namespace

TEST_CASE("CG solves an SPD system to its tolerance and reports the true residual") {
  DenseMap A{random_spd(40, 0.0, 1)};
  const std::vector<double> b = random_vector(40, 2);
  std::vector<double> x;
  const auto result = conjugate_gradient(A, IdentityPreconditioner{}, b, x, SolveControl{1e-12, 0.0, 200});
  const Eigen::VectorXd exact = A.A.ldlt().solve(Eigen::Map<const Eigen::VectorXd>(b.data(), 40));
  CHECK(result.converged);
  CHECK(result.iterations > 0);
  CHECK(result.iterations <= 40);
  CHECK(max_error(x, exact) < 1e-10);
  std::vector<double> Ax;
  A.apply(x, Ax);
  double r2 = 0.0, b2 = 0.0;
  for (int i = 0; i < 40; ++i) {
    r2 += (b[i] - Ax[i]) * (b[i] - Ax[i]);
    b2 += b[i] * b[i];
  }
  CHECK(result.relative_residual == doctest::Approx(std::sqrt(r2 / b2)).epsilon(1e-6));
  CHECK(result.relative_residual <= 10 * 1e-12);
}

TEST_CASE("Jacobi preconditioning removes a badly scaled diagonal") {
  DenseMap A{random_spd(60, 6.0, 3)};
  std::vector<double> diagonal(60);
  for (int i = 0; i < 60; ++i) diagonal[i] = A.A(i, i);
  const std::vector<double> b = random_vector(60, 4);
  std::vector<double> plain, jacobi;
  const auto r_plain = conjugate_gradient(A, IdentityPreconditioner{}, b, plain, SolveControl{1e-10, 0.0, 5000});
  const auto r_jacobi =
      conjugate_gradient(A, JacobiPreconditioner(diagonal), b, jacobi, SolveControl{1e-10, 0.0, 5000});
  CHECK(r_jacobi.converged);
  CHECK(r_jacobi.iterations * 3 < r_plain.iterations);
  const Eigen::VectorXd exact = A.A.ldlt().solve(Eigen::Map<const Eigen::VectorXd>(b.data(), 60));
  CHECK(max_error(jacobi, exact) < 1e-6);
}

TEST_CASE("CG on vector unknowns equals one scalar solve per component") {
  // y = A x applied to every component at once, as the implicit viscosity does.
  const Eigen::MatrixXd A = random_spd(25, 2.0, 5);
  std::vector<double> diagonal(25);
  for (int i = 0; i < 25; ++i) diagonal[i] = A(i, i);
  auto apply_vec = [&](const std::vector<Eigen::Vector3d>& x, std::vector<Eigen::Vector3d>& y) {
    y.assign(x.size(), Eigen::Vector3d::Zero());
    for (int i = 0; i < 25; ++i)
      for (int j = 0; j < 25; ++j) y[i] += A(i, j) * x[j];
  };
  std::vector<Eigen::Vector3d> b(25), x;
  for (int c = 0; c < 3; ++c) {
    const std::vector<double> bc = random_vector(25, 10 + c);
    for (int i = 0; i < 25; ++i) b[i][c] = bc[i];
  }
  const auto result =
      conjugate_gradient(apply_vec, JacobiPreconditioner(diagonal), b, x, SolveControl{1e-12, 0.0, 500});
  CHECK(result.converged);
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd bc(25);
    for (int i = 0; i < 25; ++i) bc[i] = b[i][c];
    const Eigen::VectorXd exact = A.ldlt().solve(bc);
    for (int i = 0; i < 25; ++i) CHECK(x[i][c] == doctest::Approx(exact[i]).epsilon(1e-9));
  }
}

TEST_CASE("CG solves a singular consistent system (Neumann Laplacian) up to its null space") {
  // The 1D Laplacian with zero-flux ends: null space = constants; b of zero mean is in range.
  const int n = 50;
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i + 1 < n; ++i) {
    L(i, i) += 1;
    L(i + 1, i + 1) += 1;
    L(i, i + 1) -= 1;
    L(i + 1, i) -= 1;
  }
  DenseMap A{L};
  std::vector<double> b = random_vector(n, 6);
  double mean = 0.0;
  for (double v : b) mean += v / n;
  for (double& v : b) v -= mean;
  std::vector<double> x;
  const auto result = conjugate_gradient(A, IdentityPreconditioner{}, b, x, SolveControl{1e-10, 0.0, 500});
  CHECK(result.converged);
  CHECK(result.relative_residual < 1e-9);
}

TEST_CASE("A zero right-hand side gives x = 0 without iterating") {
  DenseMap A{random_spd(10, 0.0, 7)};
  std::vector<double> x = random_vector(10, 8);
  const auto result = conjugate_gradient(A, IdentityPreconditioner{}, std::vector<double>(10, 0.0), x, SolveControl{});
  CHECK(result.converged);
  CHECK(result.iterations == 0);
  for (double v : x) CHECK(v == 0.0);
}

TEST_CASE("A solve capped below convergence reports it") {
  DenseMap A{random_spd(60, 6.0, 9)};
  const std::vector<double> b = random_vector(60, 10);
  std::vector<double> x;
  const auto result = conjugate_gradient(A, IdentityPreconditioner{}, b, x, SolveControl{1e-12, 0.0, 1});
  CHECK_FALSE(result.converged);
  CHECK(result.iterations == 1);
  CHECK(result.relative_residual > 1e-3);
}

TEST_CASE("An indefinite operator is a breakdown, reported as not converged") {
  DenseMap A{Eigen::Vector3d(1.0, -1.0, 2.0).asDiagonal()};
  const std::vector<double> b = {1.0, 1.0, 0.0};  // d.A d = 0 on the first direction
  std::vector<double> x;
  const auto result = conjugate_gradient(A, IdentityPreconditioner{}, b, x, SolveControl{1e-12, 0.0, 100});
  CHECK_FALSE(result.converged);
  CHECK(result.iterations == 0);
}

TEST_CASE("The initial guess is used: starting from the solution takes no iteration") {
  DenseMap A{random_spd(20, 1.0, 11)};
  const std::vector<double> b = random_vector(20, 12);
  const Eigen::VectorXd exact = A.A.ldlt().solve(Eigen::Map<const Eigen::VectorXd>(b.data(), 20));
  std::vector<double> x(exact.data(), exact.data() + 20);
  const auto result = conjugate_gradient(A, IdentityPreconditioner{}, b, x, SolveControl{1e-8, 0.0, 100});
  CHECK(result.converged);
  CHECK(result.iterations == 0);
}

TEST_CASE("vector operations: block sums give the same bits on one thread and on two") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const std::size_t n : {std::size_t{1000}, mpm::solve::kVectorBlock, 5 * mpm::solve::kVectorBlock + 17}) {
    CAPTURE(n);
    std::vector<double> a(n), b(n);
    for (std::size_t i = 0; i < n; ++i) {
      a[i] = u(rng) * std::pow(10.0, 8.0 * u(rng));  // magnitudes over 16 decades: the order shows
      b[i] = u(rng);
    }
    // The definition: each block in index order, then the blocks' sums in block order.
    double expected = 0.0;
    for (std::size_t first = 0; first < n; first += mpm::solve::kVectorBlock) {
      double block = 0.0;
      for (std::size_t i = first; i < std::min(n, first + mpm::solve::kVectorBlock); ++i) block += a[i] * b[i];
      expected += block;
    }
    double one = 0.0, two = 0.0;
    tbb::task_arena(1).execute([&] { one = mpm::solve::dot(a, b); });
    tbb::task_arena(2).execute([&] { two = mpm::solve::dot(a, b); });
    CHECK(one == expected);
    CHECK(two == expected);
    std::vector<double> c(n, 0.0);
    tbb::task_arena(2).execute(
        [&] { mpm::solve::for_each_entry(n, [&](std::size_t i) { c[i] = a[i] + 2.0 * b[i]; }); });
    for (std::size_t i = 0; i < n; ++i) REQUIRE(c[i] == a[i] + 2.0 * b[i]);
  }
  // Blocks whose sums cancel: 1e16 + 1 - 1e16 + 1 is 1 in block order and 0 in reverse.
  constexpr std::size_t block = mpm::solve::kVectorBlock;
  std::vector<double> a(4 * block, 0.0), ones(4 * block, 1.0);
  a[0] = 1e16, a[block] = 1.0, a[2 * block] = -1e16, a[3 * block] = 1.0;
  CHECK(mpm::solve::dot(a, ones) == 1.0);
}
