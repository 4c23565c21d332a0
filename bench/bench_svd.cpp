// bench_svd: nanoseconds per 3x3 SVD and per 3x3 polar decomposition, math::svd<3> (svd3,
// McAdams et al. 2011 with exact rotations) against the previous path, Eigen's JacobiSVD with
// the factors fixed up to proper rotations, in the same process on the same matrices.
//
//   bench_svd                          (1e6 matrices, best of 5)
//   bench_svd --count 100000 --repeat 3
//
// Two input sets: entries uniform in [-2, 2], and deformation gradients as the solver sees
// them, R (I + E) with R a random rotation and E symmetric with entries in [-0.1, 0.1].
// Before timing, the singular values of both implementations are compared; the program exits 1
// when they differ by more than 1e-12 relative to the largest.
#include <mpm/math/svd.h>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace mpm;

namespace {

// The previous math::svd<3>: Eigen's two-sided Jacobi SVD, a reflection in U or V moved onto
// the smallest singular value.
math::Svd<3> eigen_svd(const Mat<3>& F) {
  const Eigen::JacobiSVD<Mat<3>, Eigen::NoQRPreconditioner> jacobi(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  math::Svd<3> result{jacobi.matrixU(), jacobi.singularValues(), jacobi.matrixV()};
  if (result.U.determinant() < 0) {
    result.U.col(2) *= -1;
    result.sigma(2) *= -1;
  }
  if (result.V.determinant() < 0) {
    result.V.col(2) *= -1;
    result.sigma(2) *= -1;
  }
  return result;
}

math::Polar<3> eigen_polar(const Mat<3>& F) {
  const math::Svd<3> f = eigen_svd(F);
  return {f.U * f.V.transpose(), f.V * f.sigma.asDiagonal() * f.V.transpose()};
}

std::vector<Mat<3>> uniform_entries(int count, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> entry(-2.0, 2.0);
  std::vector<Mat<3>> matrices(count);
  for (Mat<3>& F : matrices) F = Mat<3>::NullaryExpr([&] { return entry(rng); });
  return matrices;
}

std::vector<Mat<3>> deformation_gradients(int count, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> strain(-0.1, 0.1);
  std::vector<Mat<3>> matrices(count);
  for (Mat<3>& F : matrices) {
    const Mat<3> R =
        Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized().toRotationMatrix();
    const Mat<3> E = Mat<3>::NullaryExpr([&] { return strain(rng); });
    F = R * (Mat<3>::Identity() + 0.5 * (E + E.transpose()));
  }
  return matrices;
}

// Best of `repeat` passes over all matrices, in ns per call. The sum of one entry of every
// result keeps the compiler from dropping the calls.
template <class Decomposition>
double best_ns_per_call(const std::vector<Mat<3>>& matrices, int repeat, Decomposition&& decompose, double& checksum) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeat; ++r) {
    double sum = 0.0;
    const auto start = std::chrono::steady_clock::now();
    for (const Mat<3>& F : matrices) sum += decompose(F);
    const std::chrono::duration<double, std::nano> elapsed = std::chrono::steady_clock::now() - start;
    best = std::min(best, elapsed.count() / static_cast<double>(matrices.size()));
    checksum += sum;
  }
  return best;
}

// The same for svd3 of four matrices at once (math::kSvdLanes), in ns per matrix.
double best_ns_per_call_of_four(const std::vector<Mat<3>>& matrices, int repeat, double& checksum) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < repeat; ++r) {
    double sum = 0.0;
    const auto start = std::chrono::steady_clock::now();
    math::for_each_svd<3>(
        0, matrices.size(), [&](std::size_t i) -> const Mat<3>& { return matrices[i]; },
        [](std::size_t) { return true; }, [&](std::size_t, const math::Svd<3>& f) { sum += f.U(0, 0); });
    const std::chrono::duration<double, std::nano> elapsed = std::chrono::steady_clock::now() - start;
    best = std::min(best, elapsed.count() / static_cast<double>(matrices.size()));
    checksum += sum;
  }
  return best;
}

double largest_singular_value_difference(const std::vector<Mat<3>>& matrices) {
  double worst = 0.0;
  for (const Mat<3>& F : matrices) {
    const Vec<3> expected = eigen_svd(F).sigma, sigma = math::svd3(F).sigma;
    worst = std::max(worst, (sigma - expected).cwiseAbs().maxCoeff() / expected(0));
  }
  return worst;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"3x3 SVD and polar decomposition: math::svd<3> against Eigen's JacobiSVD"};
  int count = 1000000, repeat = 5;
  app.add_option("--count", count, "matrices per input set")->check(CLI::PositiveNumber);
  app.add_option("--repeat", repeat, "timed passes over the matrices; the best is reported")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);

  std::mt19937_64 rng(2011);
  const std::vector<std::pair<std::string, std::vector<Mat<3>>>> inputs = {
      {"entries in [-2, 2]", uniform_entries(count, rng)},
      {"R (I + E), E_ij in [-0.1, 0.1]", deformation_gradients(count, rng)},
  };

  double checksum = 0.0;
  bool agree = true;
  std::printf("%d matrices per set, best of %d passes, ns per call\n\n", count, repeat);
  std::printf("| input | Eigen SVD | svd3 | x | svd3 of four | x | Eigen polar | polar | x | max sigma diff |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [name, matrices] : inputs) {
    const double difference = largest_singular_value_difference(matrices);
    agree = agree && difference <= 1e-12;
    const double eigen_ns = best_ns_per_call(
        matrices, repeat, [](const Mat<3>& F) { return eigen_svd(F).U(0, 0); }, checksum);
    const double svd3_ns = best_ns_per_call(
        matrices, repeat, [](const Mat<3>& F) { return math::svd3(F).U(0, 0); }, checksum);
    const double lanes_ns = best_ns_per_call_of_four(matrices, repeat, checksum);
    const double eigen_polar_ns = best_ns_per_call(
        matrices, repeat, [](const Mat<3>& F) { return eigen_polar(F).R(0, 0); }, checksum);
    const double polar_ns = best_ns_per_call(
        matrices, repeat, [](const Mat<3>& F) { return math::polar<3>(F).R(0, 0); }, checksum);
    std::printf("| %s | %.1f | %.1f | %.2f | %.1f | %.2f | %.1f | %.1f | %.2f | %.1e |\n", name.c_str(), eigen_ns,
                svd3_ns, eigen_ns / svd3_ns, lanes_ns, eigen_ns / lanes_ns, eigen_polar_ns, polar_ns,
                eigen_polar_ns / polar_ns, difference);
  }
  std::printf("\n(checksum %.6e)\n", checksum);
  if (!agree) {
    std::fprintf(stderr, "bench_svd: singular values differ from Eigen's by more than 1e-12\n");
    return 1;
  }
  return 0;
}
