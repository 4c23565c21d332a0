// The per-particle algebra of the CUDA back-end (device_math.cuh, compiled here for the host)
// against the CPU library it mirrors: the SVD against math::svd3, the Kirchhoff stress of each
// hyperelastic model against model.first_piola(F) F^T, and the Drucker-Prager and von Mises
// return maps against plasticity::DruckerPrager / VonMises, on random, inverted and
// near-degenerate F. Double precision must agree to round-off (1e-12), single to 1e-5. Runs
// without a GPU (label unit).
#include <doctest/doctest.h>

#include "device_math.cuh"

#include <mpm/solid/material.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

using namespace mpm;
namespace dev = mpm::cuda::detail;

namespace {

template <class T>
dev::M3<T> to_device(const Mat<3>& F) {
  dev::M3<T> d;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) d(r, c) = T(F(r, c));
  return d;
}

template <class T>
Mat<3> from_device(const dev::M3<T>& d) {
  Mat<3> F;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) F(r, c) = double(d(r, c));
  return F;
}

//! Random F: rotations times stretches from 0.33 to 3, a few inverted, some with repeated
//! singular values or nearly flat. Not inverted and repeated at once: a reflection within a plane
//! of equal stretches has no unique rotation-variant SVD, and the CPU's choice is as arbitrary.
std::vector<Mat<3>> samples() {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> normal;
  const auto rotation = [&] {
    return Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized().toRotationMatrix();
  };
  std::vector<Mat<3>> all;
  for (int i = 0; i < 400; ++i) {
    Vec<3> s(std::exp(1.1 * u(rng)), std::exp(1.1 * u(rng)), std::exp(1.1 * u(rng)));
    if (i % 7 == 0)
      s[2] = -s[2];  // inverted
    else if (i % 11 == 0)
      s[1] = s[0];                 // repeated
    if (i % 13 == 0) s[2] = 0.05;  // nearly flat
    all.push_back(rotation() * s.asDiagonal() * rotation().transpose());
  }
  all.push_back(Mat<3>::Identity());
  return all;
}

Material<3> material(const std::string& yaml) { return parse_material<3>(Config::parse(yaml)); }

dev::DeviceMaterial device_material(const Material<3>& m) {
  dev::DeviceMaterial d{};
  d.mu = m.lame.mu;
  d.lambda = m.lame.lambda;
  d.elasticity = std::visit(
      [](const auto& e) {
        using E = std::decay_t<decltype(e)>;
        if constexpr (std::is_same_v<E, constitutive::FixedCorotated<3>>) return dev::Elasticity::fixed_corotated;
        if constexpr (std::is_same_v<E, constitutive::NeoHookean<3>>) return dev::Elasticity::neo_hookean;
        return dev::Elasticity::hencky_stvk;
      },
      m.elastic);
  if (const auto* dp = std::get_if<plasticity::DruckerPrager<3>>(&m.plasticity)) {
    d.plasticity = dev::Plasticity::drucker_prager;
    d.alpha = dp->cone_alpha();
    d.k = dp->cone_k();
  } else if (const auto* vm = std::get_if<plasticity::VonMises<3>>(&m.plasticity)) {
    d.plasticity = dev::Plasticity::von_mises;
    d.yield_stress = vm->yield_stress();
  }
  return d;
}

template <class T>
Mat<3> device_kirchhoff(const dev::DeviceMaterial& m, const dev::Svd3<T>& f) {
  T tau[6];
  dev::kirchhoff(m, f, tau);
  Mat<3> t;
  t << tau[0], tau[3], tau[4], tau[3], tau[1], tau[5], tau[4], tau[5], tau[2];
  return t;
}

const char* kElastic[] = {"{density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: fixed_corotated}",
                          "{density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: neo_hookean}",
                          "{density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk}"};
const char* kPlastic[] = {
    "{density: 2650, youngs_modulus: 3.0e6, poisson_ratio: 0.3, elasticity: hencky_stvk,"
    " plasticity: {model: drucker_prager, friction_angle: 32, cohesion: 2000}}",
    "{density: 1000, youngs_modulus: 5.0e4, poisson_ratio: 0.35, elasticity: hencky_stvk,"
    " plasticity: {model: von_mises, yield_stress: 300}}"};

template <class T>
void check_against_cpu(double tolerance) {
  double svd = 0.0, stress = 0.0, map = 0.0;
  for (const Mat<3>& F : samples()) {
    const math::Svd<3> cpu = math::svd3(F);
    const dev::Svd3<T> d = dev::svd3(to_device<T>(F));
    // U and V are unique only up to repeated singular values: compare sigma and U diag(sigma) V^T.
    for (int i = 0; i < 3; ++i) svd = std::max(svd, std::abs(double(d.sigma[i]) - cpu.sigma[i]) / cpu.sigma[0]);
    svd = std::max(svd, (from_device(dev::compose(d.U, d.sigma, d.V)) - F).norm() / F.norm());
    svd =
        std::max(svd, std::abs(from_device(d.U).determinant() - 1.0) + std::abs(from_device(d.V).determinant() - 1.0));
    for (const char* yaml : kElastic) {
      const Material<3> m = material(yaml);
      const Mat<3> expected = m.kirchhoff(F);
      stress =
          std::max(stress, (device_kirchhoff(device_material(m), d) - expected).norm() / (expected.norm() + m.lame.mu));
    }
    for (const char* yaml : kPlastic) {
      const Material<3> m = material(yaml);
      for (const double start : {0.0, 0.05}) {  // a stored volume correction too (sand)
        Mat<3> Fc = F;
        double plastic_cpu = start;
        std::visit(
            [&](const auto& model) {
              if constexpr (!std::is_same_v<std::decay_t<decltype(model)>, plasticity::NoPlasticity>)
                model.project(Fc, plastic_cpu);
            },
            m.plasticity);
        dev::M3<T> Fd = to_device<T>(F);
        T plastic_device = T(start);
        dev::Svd3<T> f;
        dev::return_map(device_material(m), Fd, plastic_device, f);
        map = std::max(map, (from_device(Fd) - Fc).cwiseAbs().maxCoeff() / Fc.cwiseAbs().maxCoeff());
        map = std::max(map, std::abs(double(plastic_device) - plastic_cpu));
      }
    }
  }
  MESSAGE("device math vs CPU: svd ", svd, ", kirchhoff ", stress, ", return maps ", map);
  CHECK(svd < tolerance);
  CHECK(stress < tolerance);
  CHECK(map < tolerance);
}

}  // namespace

TEST_CASE("the device's SVD, stresses and return maps equal the CPU's in double precision") {
  check_against_cpu<double>(1e-12);
}

TEST_CASE("and agree to single precision in float") { check_against_cpu<float>(2e-5); }
