// Dilatant Drucker-Prager sand (plasticity/drucker_prager.h): the return map against its own
// definition (the cone of mu_cone + tan psi, plastic volume sqrt(2) tan psi dgamma, the packing
// kept through the map), and the behaviour it exists for: under undrained (isochoric) shear a
// dense sand builds pressure and a loose one loses it; under drained shear at constant pressure
// both reach the critical packing. The principal strains are taken with Eigen's JacobiSVD, not
// with the SVD the map uses.
#include <doctest/doctest.h>

#include <mpm/constitutive/hencky_stvk.h>
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/plasticity/drucker_prager.h>
#include <mpm/solid/material.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

using namespace mpm;

namespace {

const constitutive::Lame kLame = constitutive::Lame::from_youngs_poisson(1e6, 0.3);
constexpr double kFriction = 30.0, kK = 4.0, kCritical = 0.58;

template <int dim>
plasticity::DruckerPrager<dim> sand(double dilatancy = kK) {
  return {kFriction, 0.0, kLame, {.dilatancy = dilatancy, .critical_packing = kCritical}};
}

//! The cone's own friction coefficient alpha (drucker_prager.h).
double cone_alpha() {
  const double s = std::sin(kFriction * std::numbers::pi / 180.0);
  return std::sqrt(2.0 / 3.0) * 2.0 * s / (3.0 - s);
}

template <int dim>
Vec<dim> log_singular_values(const Mat<dim>& F) {
  return Eigen::JacobiSVD<Mat<dim>>(F).singularValues().array().log();
}

template <int dim>
Mat<dim> kirchhoff(const Mat<dim>& F) {
  const constitutive::HenckyStVK<dim> hencky{kLame.mu, kLame.lambda};
  return hencky.first_piola(F) * F.transpose();
}

//! ||dev tau|| / -tr tau: on the cone it is alpha (of the current packing).
template <int dim>
double stress_ratio(const Mat<dim>& tau) {
  const double trace = tau.trace();
  return (tau - trace / dim * Mat<dim>::Identity()).norm() / -trace;
}

template <int dim>
Mat<dim> random_rotation(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-std::numbers::pi, std::numbers::pi);
  if constexpr (dim == 2) {
    return Eigen::Rotation2D<double>(u(rng)).toRotationMatrix();
  } else {
    const Vec<3> axis = Vec<3>(u(rng), u(rng), u(rng)).normalized();
    return Eigen::AngleAxis<double>(u(rng), axis).toRotationMatrix();
  }
}

//! Simple shear by `gamma` in the x-y plane.
template <int dim>
Mat<dim> shear(double gamma) {
  Mat<dim> S = Mat<dim>::Identity();
  S(0, 1) = gamma;
  return S;
}

//! A trial F^E with singular values in [0.95, 1.02] between random rotations.
template <int dim>
Mat<dim> random_trial(std::mt19937& rng) {
  std::uniform_real_distribution<double> stretch(0.95, 1.02);
  Vec<dim> s;
  for (int a = 0; a < dim; ++a) s(a) = stretch(rng);
  return random_rotation<dim>(rng) * s.asDiagonal() * random_rotation<dim>(rng);
}

//! A material point sheared by `gamma` in one step of dt, drained: the volume scaled so that
//! the pressure after the return map is p_target (bisection: the pressure grows monotonically
//! with compression). Fe, plastic and (a dilatant model's) rest packing move to the new state.
template <int dim>
void shear_drained(const plasticity::DruckerPrager<dim>& model, double gamma, double dt, double p_target, Mat<dim>& Fe,
                   double& plastic, double* rest) {
  const Mat<dim> base = shear<dim>(gamma) * Fe;
  double lo = 0.9, hi = 1.1, next_plastic = 0.0, next_rest = 0.0;
  Mat<dim> next;
  for (int it = 0; it < 60; ++it) {
    const double scale = 0.5 * (lo + hi);
    next = scale * base;
    next_plastic = plastic;
    next_rest = rest ? *rest : 0.0;
    model.project(next, next_plastic, rest ? &next_rest : nullptr, dt);
    (-kirchhoff(next).trace() / dim > p_target ? lo : hi) = scale;
  }
  Fe = next;
  plastic = next_plastic;
  if (rest) *rest = next_rest;
}

}  // namespace

TEST_CASE_TEMPLATE("dilatant return map: on the cone of mu + tan psi, plastic volume sqrt(2) tan psi dgamma", Matrix,
                   Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = sand<dim>();
  std::mt19937 rng(1998);
  int on_cone = 0, at_apex = 0;
  for (const double phi : {0.52, 0.56, 0.58, 0.60, 0.64}) {
    const double tan_psi = kK * (phi - kCritical);
    const double alpha = cone_alpha() + std::numbers::sqrt2 * tan_psi / dim;
    for (int n = 0; n < 100; ++n) {
      const Mat<dim> trial = random_trial<dim>(rng);
      CAPTURE(phi);
      CAPTURE(trial);
      Mat<dim> Fe = trial;
      double plastic = 0.0, rest = phi * trial.determinant();  // the packing is phi now
      model.project(Fe, plastic, &rest, 0.0);
      CHECK(rest / Fe.determinant() == doctest::Approx(phi).epsilon(1e-12));  // total volume kept
      const Mat<dim> tau = kirchhoff(Fe);
      const double scale = kirchhoff(trial).norm();
      if (plastic > 0.0 || tau.trace() > -1e-9 * scale) {  // II: stress free at the apex
        CHECK(tau.norm() <= 1e-9 * scale);
        ++at_apex;
        continue;
      }
      // Admissible on the cone of this packing; on it where the map moved F^E.
      CHECK(stress_ratio(tau) <= alpha * (1.0 + 1e-10));
      if ((Fe - trial).norm() == 0.0) continue;
      CHECK(stress_ratio(tau) == doctest::Approx(alpha).epsilon(1e-9));
      ++on_cone;
      // The flow: the deviator shrinks by dgamma, the volume by sqrt(2) tan psi dgamma.
      const Vec<dim> before = log_singular_values(trial), after = log_singular_values(Fe);
      const auto dev_norm = [](const Vec<dim>& e) { return (e.array() - e.mean()).matrix().norm(); };
      const double dgamma = dev_norm(before) - dev_norm(after);
      CHECK(dgamma > 0.0);
      CHECK(after.sum() - before.sum() ==
            doctest::Approx(-std::numbers::sqrt2 * tan_psi * dgamma).scale(1e-3).epsilon(1e-9));
    }
  }
  CHECK(on_cone > 100);
  CHECK(at_apex > 20);

  // K = 0 is the plain map, bit for bit, and leaves the packing alone.
  const plasticity::DruckerPrager<dim> plain(kFriction, 0.0, kLame), none = sand<dim>(0.0);
  for (int n = 0; n < 50; ++n) {
    const Mat<dim> trial = random_trial<dim>(rng);
    Mat<dim> a = trial, b = trial;
    double va = 0.0, vb = 0.0, rest = 0.6;
    plain.project(a, va);
    none.project(b, vb, &rest, 0.0);
    CHECK(a == b);
    CHECK(va == vb);
    CHECK(rest == 0.6);
  }
}

TEST_CASE_TEMPLATE("undrained shear: a dense sand builds pressure, a loose one liquefies, a critical one holds", Matrix,
                   Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = sand<dim>();
  // Isotropic compression by 1 %, then 0.5 of simple shear at constant volume in 500 steps.
  const auto pressure_after_shear = [&](double phi, double gamma) {
    Mat<dim> Fe = 0.99 * Mat<dim>::Identity();
    double plastic = 0.0, rest = phi * Fe.determinant();
    for (int n = 0; n < 500; ++n) {
      Fe = shear<dim>(gamma / 500) * Fe;
      model.project(Fe, plastic, &rest, 0.0);
    }
    CHECK(rest / Fe.determinant() == doctest::Approx(phi).epsilon(1e-12));  // isochoric: phi fixed
    return -kirchhoff(Fe).trace() / dim;
  };
  const double p0 = -kirchhoff(Mat<dim>(0.99 * Mat<dim>::Identity())).trace() / dim;
  CHECK(pressure_after_shear(0.58, 0.5) == doctest::Approx(p0).epsilon(1e-10));  // psi = 0: no volume change
  CHECK(pressure_after_shear(0.62, 0.5) > 2.0 * p0);                             // dilatancy held back
  CHECK(pressure_after_shear(0.54, 0.5) < 1e-9 * p0);                            // contraction: no contacts left
  CHECK(pressure_after_shear(0.62, 0.5) > pressure_after_shear(0.60, 0.5));      // denser, stronger
}

TEST_CASE_TEMPLATE("drained shear at constant pressure: dense and loose sand reach the critical packing", Matrix,
                   Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = sand<dim>();
  const double p_target = 2e3;  // [Pa]
  struct Path {
    double packing, peak_ratio, final_ratio;
  };
  // Simple shear by 3 in 3000 steps at the pressure p_target.
  const auto shear_to_critical = [&](double phi) {
    Mat<dim> Fe = Mat<dim>::Identity();
    double plastic = 0.0, rest = phi, peak = 0.0, ratio = 0.0;
    for (int n = 0; n < 3000; ++n) {
      shear_drained(model, 1e-3, 0.0, p_target, Fe, plastic, &rest);
      ratio = stress_ratio(kirchhoff(Fe));
      peak = std::max(peak, ratio);
    }
    CHECK(-kirchhoff(Fe).trace() / dim == doctest::Approx(p_target).epsilon(1e-6));
    return Path{rest / Fe.determinant(), peak, ratio};
  };
  const Path dense = shear_to_critical(0.62), loose = shear_to_critical(0.54);
  CAPTURE(dense.packing);
  CAPTURE(loose.packing);
  CHECK(std::abs(dense.packing - kCritical) < 2e-3);  // dilated
  CHECK(std::abs(loose.packing - kCritical) < 2e-3);  // compacted
  CHECK(dense.packing > kCritical);                   // from above and below, without overshoot
  CHECK(loose.packing < kCritical);
  // At the critical state both are on the cone of the plain friction angle; the dense sand
  // passed a peak above it.
  CHECK(dense.final_ratio == doctest::Approx(cone_alpha()).epsilon(2e-2));
  CHECK(loose.final_ratio == doctest::Approx(cone_alpha()).epsilon(2e-2));
  CHECK(dense.peak_ratio > cone_alpha() + std::numbers::sqrt2 * kK * 0.02 / dim);
}

TEST_CASE("dilatant sand: scene keys and their errors") {
  const std::string base =
      "density: 2650\nyoungs_modulus: 1e6\npoisson_ratio: 0.3\nelasticity: hencky_stvk\nplasticity: {model: "
      "drucker_prager, friction_angle: 30";
  const Material<2> m = parse_material<2>(Config::parse(base + ", dilatancy: 4.09, critical_packing: 0.58}\n"));
  const auto& dp = std::get<plasticity::DruckerPrager<2>>(m.plasticity);
  CHECK(dp.dilatant());
  CHECK(dp.flow().dilatancy == 4.09);
  CHECK(dp.flow().critical_packing == 0.58);
  CHECK_FALSE(dp.rate_dependent());
  CHECK_FALSE(
      std::get<plasticity::DruckerPrager<2>>(parse_material<2>(Config::parse(base + "}\n")).plasticity).dilatant());
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", dilatancy: -1, critical_packing: 0.58}\n")),
                       doctest::Contains("plasticity.dilatancy"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", dilatancy: 4, critical_packing: 1.2}\n")),
                       doctest::Contains("plasticity.critical_packing"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", dilatancy: 4}\n")),
                       doctest::Contains("critical_packing"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", critical_packing: 0.58}\n")),
                       doctest::Contains("needs a dilatancy coefficient"), InputError);

  // mu(J): mu_2 below the static friction (mu_1 = 0.462 at 30 degrees in 2D) is refused.
  const Material<2> fast =
      parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7, j_0: 0.005, viscosity: 0.012}}\n"));
  const auto& rated = std::get<plasticity::DruckerPrager<2>>(fast.plasticity);
  CHECK(rated.rate_dependent());
  CHECK(rated.flow().mu_2 == 0.7);
  CHECK(rated.flow().viscosity == 0.012);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.3, viscosity: 0.012}}\n")),
                       doctest::Contains("plasticity.rate.mu_2"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7, viscosity: 0}}\n")),
                       doctest::Contains("plasticity.rate.viscosity"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7}}\n")),
                       doctest::Contains("viscosity"), InputError);
  // mu(I): a grain diameter selects the inertial number; I_0 and rho_s default to 0.279 and the
  // material's density; the keys of J are refused beside it, and those of I without it.
  const Material<2> dry = parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7, grain_diameter: 5.0e-4}}\n"));
  const auto& inertial = std::get<plasticity::DruckerPrager<2>>(dry.plasticity);
  CHECK(inertial.rate_dependent());
  CHECK(inertial.flow().inertial());
  CHECK(inertial.flow().j_0 == 0.279);
  CHECK(inertial.flow().grain_density == 2650.0);
  CHECK_THROWS_WITH_AS(
      parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7, grain_diameter: 5.0e-4, viscosity: 0.01}}\n")),
      doctest::Contains("plasticity.rate.viscosity"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7, grain_diameter: -1}}\n")),
                       doctest::Contains("plasticity.rate.grain_diameter"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7, i_0: 0.3, viscosity: 0.01}}\n")),
                       doctest::Contains("plasticity.rate.i_0"), InputError);
}

namespace {
constexpr double kMu2 = 0.7, kJ0 = 0.005, kEta = 0.012;

template <int dim>
plasticity::DruckerPrager<dim> rated_sand() {
  return {kFriction, 0.0, kLame, {.mu_2 = kMu2, .j_0 = kJ0, .viscosity = kEta}};
}

}  // namespace

TEST_CASE_TEMPLATE("mu(J): on the cone of the friction of its own shear rate; slow flow is rate independent", Matrix,
                   Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = rated_sand<dim>(), plain(kFriction, 0.0, kLame);
  const double mu_1 = cone_alpha() * dim / std::numbers::sqrt2;
  std::mt19937 rng(2011);
  int flowing = 0;
  for (const double dt : {1e-5, 1e-3, 1e-1}) {
    for (int n = 0; n < 100; ++n) {
      const Mat<dim> trial = random_trial<dim>(rng);
      CAPTURE(dt);
      CAPTURE(trial);
      Mat<dim> Fe = trial, Fp = trial;
      double plastic = 0.0, plain_plastic = 0.0;
      model.project(Fe, plastic, nullptr, dt);
      plain.project(Fp, plain_plastic);
      const Mat<dim> tau = kirchhoff(Fe);
      if (plastic > 0.0 || (Fe - trial).norm() == 0.0) continue;  // apex or elastic: as the plain map
      ++flowing;
      // J from the returned state alone: dgamma from the principal strains, P from tau.
      const Vec<dim> before = log_singular_values(trial), after = log_singular_values(Fe);
      const auto dev_norm = [](const Vec<dim>& e) { return (e.array() - e.mean()).matrix().norm(); };
      const double dgamma = dev_norm(before) - dev_norm(after);
      const double J = kEta * std::numbers::sqrt2 * dgamma / dt / (-tau.trace() / dim);
      const double mu = mu_1 + (kMu2 - mu_1) * J / (J + kJ0);
      CHECK(stress_ratio(tau) == doctest::Approx(mu * std::numbers::sqrt2 / dim).epsilon(1e-9));
      CHECK(stress_ratio(tau) >= stress_ratio(kirchhoff(Fp)) * (1.0 - 1e-12));  // never weaker
      if (dt == 1e-1) CHECK((Fe - Fp).norm() <= 0.05 * (trial - Fp).norm());    // slow: nearly the plain map
    }
  }
  CHECK(flowing > 50);
}

TEST_CASE_TEMPLATE("mu(J): steady simple shear at an imposed rate and pressure reaches mu(eta gamma_dot / P)", Matrix,
                   Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = rated_sand<dim>();
  const double mu_1 = cone_alpha() * dim / std::numbers::sqrt2, p_target = 200.0, dt = 1e-3;
  for (const double gamma_dot : {0.1, 10.0, 100.0}) {
    // Shear by gamma_dot dt per step at the pressure p_target.
    Mat<dim> Fe = Mat<dim>::Identity();
    double plastic = 0.0;
    for (int n = 0; n < 4000; ++n) shear_drained(model, gamma_dot * dt, dt, p_target, Fe, plastic, nullptr);
    const double J = kEta * gamma_dot / p_target;
    const double mu = mu_1 + (kMu2 - mu_1) * J / (J + kJ0);
    CAPTURE(gamma_dot);
    CHECK(stress_ratio(kirchhoff(Fe)) == doctest::Approx(mu * std::numbers::sqrt2 / dim).epsilon(2e-3));
  }
}

TEST_CASE_TEMPLATE(
    "mu(I): steady simple shear at an imposed rate and pressure reaches mu(d gamma_dot / sqrt(P / "
    "rho_s))",
    Matrix, Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  constexpr double d = 5e-4, rho_s = 2650.0, I0 = 0.279;
  const plasticity::DruckerPrager<dim> model(kFriction, 0.0, kLame,
                                             {.mu_2 = kMu2, .j_0 = I0, .grain_diameter = d, .grain_density = rho_s});
  const double mu_1 = cone_alpha() * dim / std::numbers::sqrt2, p_target = 200.0, dt = 1e-3;
  for (const double gamma_dot : {1.0, 50.0, 500.0}) {
    Mat<dim> Fe = Mat<dim>::Identity();
    double plastic = 0.0;
    for (int n = 0; n < 4000; ++n) shear_drained(model, gamma_dot * dt, dt, p_target, Fe, plastic, nullptr);
    const double I = d * gamma_dot / std::sqrt(p_target / rho_s);  // 0.0018, 0.091, 0.91
    const double mu = mu_1 + (kMu2 - mu_1) * I / (I + I0);
    CAPTURE(gamma_dot);
    CHECK(stress_ratio(kirchhoff(Fe)) == doctest::Approx(mu * std::numbers::sqrt2 / dim).epsilon(2e-3));
  }
}

namespace {
//! Boyer et al. 2011's suspension viscosity written out from their eq. 6 and phi(J) (not the
//! model's function): J = (phi_c / phi - 1)^2, eta_v = eta_f mu(J) / J with the hydrodynamic
//! terms of mu(J), J held at or above j_min.
template <int dim>
double boyer_viscosity(double phi, double j_min) {
  const double mu_1 = cone_alpha() * dim / std::numbers::sqrt2;
  const double J = std::max(std::pow(kCritical / phi - 1.0, 2), j_min);
  const double mu = mu_1 + (kMu2 - mu_1) / (1.0 + kJ0 / J) + J + 2.5 * kCritical * std::sqrt(J);
  return kEta * mu / J;
}

template <int dim>
plasticity::DruckerPrager<dim> suspension_sand(double j_min = 1e-3) {
  return {kFriction,
          0.0,
          kLame,
          {.dilatancy = kK,
           .critical_packing = kCritical,
           .mu_2 = kMu2,
           .j_0 = kJ0,
           .viscosity = kEta,
           .suspension = true,
           .j_min = j_min}};
}

//! tau_xy after steady simple shear at gamma_dot at constant volume (the packing stays phi).
template <int dim>
double steady_shear_stress(const plasticity::DruckerPrager<dim>& model, double phi, double gamma_dot, double dt) {
  Mat<dim> Fe = Mat<dim>::Identity();
  double plastic = 0.0, rest = phi;
  for (int n = 0; n < 3000; ++n) {
    Fe = shear<dim>(gamma_dot * dt) * Fe;
    model.project(Fe, plastic, &rest, dt);
  }
  CHECK(rest / Fe.determinant() == doctest::Approx(phi).epsilon(1e-12));
  // Liquefied: the deviator is all the stress (no pressure, no tension).
  const Mat<dim> tau = kirchhoff(Fe);
  CHECK(std::abs(tau.trace()) <= 1e-13 * (dim * kLame.lambda + 2.0 * kLame.mu));  // round-off of the bulk modulus
  return tau(0, 1);
}
}  // namespace

TEST_CASE_TEMPLATE("suspension: a liquefied loose sand in steady shear is a fluid of Boyer's viscosity", Matrix, Mat<2>,
                   Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = suspension_sand<dim>(), without = sand<dim>();
  // At phi = 0.55 (J = 3.0e-3) eta_v is about 200 eta_f; at 0.57 J is below j_min: the cap.
  for (const double phi : {0.50, 0.55, 0.57}) {
    const double eta = boyer_viscosity<dim>(phi, 1e-3);
    CHECK(model.suspension_viscosity(phi) == doctest::Approx(eta).epsilon(1e-12));
    // Steps shorter and longer than the Maxwell time eta / mu (1e-6 .. 2e-5 s here).
    for (const double dt : {1e-6, 1e-4, 1e-3})
      for (const double gamma_dot : {1.0, 30.0}) {
        CAPTURE(phi);
        CAPTURE(dt);
        CAPTURE(gamma_dot);
        CHECK(steady_shear_stress(model, phi, gamma_dot, dt) == doctest::Approx(eta * gamma_dot).epsilon(1e-3));
      }
    // Without the suspension the liquefied sand carries no shear stress at all.
    CHECK(std::abs(steady_shear_stress(without, phi, 1.0, 1e-4)) < 1e-9);
  }
  // By hand in 2D (mu_1 = 0.462 at 30 degrees): J = 2.975e-3, mu_c = 0.5508, eta_v / eta_f =
  // 185.1 + 1 + 26.6.
  if (dim == 2) CHECK(model.suspension_viscosity(0.55) / kEta == doctest::Approx(212.7).epsilon(1e-3));
}

TEST_CASE_TEMPLATE("suspension: frictional sand under pressure keeps mu(J); the stress stays within the trial's",
                   Matrix, Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = suspension_sand<dim>(), rated = rated_sand<dim>();
  const double mu_1 = cone_alpha() * dim / std::numbers::sqrt2, p_target = 200.0, dt = 1e-3, gamma_dot = 1.0;
  // Drained shear from the critical packing: the viscous strength 2 eta_v(j_min) gamma_dot is
  // a few Pa against mu P of about 90 Pa, so the flow lands on the cone of mu(J) as without it.
  Mat<dim> Fe = Mat<dim>::Identity();
  double plastic = 0.0, rest = kCritical;
  for (int n = 0; n < 3000; ++n) shear_drained(model, gamma_dot * dt, dt, p_target, Fe, plastic, &rest);
  const double J = kEta * gamma_dot / p_target;
  CHECK(stress_ratio(kirchhoff(Fe)) ==
        doctest::Approx((mu_1 + (kMu2 - mu_1) * J / (J + kJ0)) * std::numbers::sqrt2 / dim).epsilon(2e-3));
  // Random trials near jamming with a nearly unbounded viscosity (j_min 1e-9): the returned
  // deviatoric stress is at most the trial's (so the elastic wave's step stays stable), and
  // nearly all of it is kept.
  const plasticity::DruckerPrager<dim> stiff = suspension_sand<dim>(1e-9);
  const auto dev_norm = [](const Mat<dim>& tau) { return (tau - tau.trace() / dim * Mat<dim>::Identity()).norm(); };
  std::mt19937 rng(2011);
  int kept = 0;
  for (int n = 0; n < 200; ++n) {
    const Mat<dim> trial = random_trial<dim>(rng);
    Mat<dim> returned = trial;
    double v = 0.0, packing = 0.57999 * trial.determinant();
    stiff.project(returned, v, &packing, 1e-3);
    const double before = dev_norm(kirchhoff(trial)), after = dev_norm(kirchhoff(returned));
    CHECK(after <= before * (1.0 + 1e-12));
    kept += after > 0.99 * before;
  }
  CHECK(kept == 200);
  CHECK(rated.suspension_viscosity(0.55) == 0.0);
}

TEST_CASE_TEMPLATE("suspension: a loose sand that dilates past the apex keeps only its viscous deviator", Matrix,
                   Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> model = suspension_sand<dim>();
  // A slightly compressed trial (trace -0.002) sheared by 0.01: it yields (case III), and the
  // loose packing (phi = 0.50, tan psi = -0.32) adds more volume than the compression held, so
  // the returned state goes to the apex (trace 0) with the viscous part of the deviator left,
  // (1 - mu dt / (mu dt + eta_v)) of the trial's.
  Vec<dim> eps = Vec<dim>::Constant(-0.002 / dim);
  eps(0) += 0.01;
  eps(1) -= 0.01;
  const Mat<dim> trial = Mat<dim>(eps.array().exp().matrix().asDiagonal());
  Mat<dim> Fe = trial;
  double plastic = 0.0, rest = 0.50 * trial.determinant();
  const double dt = 1e-3;
  REQUIRE(model.project(Fe, plastic, &rest, dt));
  const double relax = kLame.mu * dt, kept = 1.0 - relax / (relax + boyer_viscosity<dim>(0.50, 1e-3));
  const Vec<dim> after = log_singular_values(Fe);  // sorted: 0.01 kept, (0), -0.01 kept
  CHECK(std::abs(after.sum()) < 1e-12);
  CHECK(after(0) == doctest::Approx(0.01 * kept).epsilon(1e-9));
  CHECK(after(dim - 1) == doctest::Approx(-0.01 * kept).epsilon(1e-9));
  CHECK(kept > 1e-4);  // a deviator is left to test
}

TEST_CASE("suspension: scene keys and their errors") {
  const std::string base =
      "density: 2500\nyoungs_modulus: 5e4\npoisson_ratio: 0.3\nelasticity: hencky_stvk\nplasticity: {model: "
      "drucker_prager, friction_angle: 30";
  const std::string dilatant = base + ", dilatancy: 4.09, critical_packing: 0.58";
  const Material<2> m =
      parse_material<2>(Config::parse(dilatant + ", rate: {mu_2: 0.7, viscosity: 0.012, suspension: true}}\n"));
  const auto& dp = std::get<plasticity::DruckerPrager<2>>(m.plasticity);
  CHECK(dp.flow().suspension);
  CHECK(dp.flow().j_min == 1e-3);
  CHECK(dp.suspension_viscosity(0.55) > 100 * 0.012);
  const Material<2> plain = parse_material<2>(Config::parse(dilatant + ", rate: {mu_2: 0.7, viscosity: 0.012}}\n"));
  CHECK_FALSE(std::get<plasticity::DruckerPrager<2>>(plain.plasticity).flow().suspension);
  CHECK_THROWS_WITH_AS(
      parse_material<2>(Config::parse(base + ", rate: {mu_2: 0.7, viscosity: 0.012, suspension: true}}\n")),
      doctest::Contains("plasticity.rate.suspension"), InputError);
  CHECK_THROWS_WITH_AS(parse_material<2>(Config::parse(
                           dilatant + ", rate: {mu_2: 0.7, viscosity: 0.012, suspension: true, j_min: 1.5}}\n")),
                       doctest::Contains("plasticity.rate.j_min"), InputError);
  CHECK_THROWS_WITH_AS(
      parse_material<2>(Config::parse(dilatant + ", rate: {mu_2: 0.7, viscosity: 0.012, j_min: 1e-3}}\n")),
      doctest::Contains("plasticity.rate.j_min"), InputError);
  CHECK_THROWS_WITH_AS(
      parse_material<2>(Config::parse(dilatant + ", rate: {mu_2: 0.7, grain_diameter: 5e-4, suspension: true}}\n")),
      doctest::Contains("suspension"), InputError);
  CHECK_THROWS_AS(plasticity::DruckerPrager<2>(30, 0, kLame, {.suspension = true}), InputError);
}

TEST_CASE("dilatant sand in a solid scene: the body's packing, refused for another material") {
  const std::string head = R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 0.6]}
grid: {dx: 0.05}
materials:
  - {name: sand, density: 2650, youngs_modulus: 1.0e6, poisson_ratio: 0.3, elasticity: hencky_stvk,
     plasticity: {model: drucker_prager, friction_angle: 30, dilatancy: 4, critical_packing: 0.58}}
  - {name: jelly, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3}
time: {end: 0.1}
gravity: [0, -9.81]
bodies:
)";
  const solid::SolidScene<2> scene = solid::load_solid_scene<2>(
      Config::parse(head + "  - {shape: box, lo: [0.2, 0.2], hi: [0.4, 0.4], material: sand, packing_fraction: 0.62, "
                           "stretch: [1, 0.9]}\n  - {shape: box, lo: [0.6, 0.2], hi: [0.8, 0.4], material: sand}\n"));
  const Particles<2>& P = scene.state.particles;
  const std::vector<double>* rest = P.find_channel<double>(solid::kRestPacking);
  REQUIRE(rest != nullptr);
  int set = 0, unknown = 0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (P.x[p][0] < 0.5) {
      CHECK((*rest)[p] == doctest::Approx(0.62 * 0.9).epsilon(1e-15));  // phi det F^E at the start
      ++set;
    } else {
      CHECK(std::isnan((*rest)[p]));  // no key: the return map starts it at phi_c
      ++unknown;
    }
  }
  CHECK(set > 0);
  CHECK(unknown > 0);
  CHECK_THROWS_WITH_AS(
      solid::load_solid_scene<2>(Config::parse(
          head + "  - {shape: box, lo: [0.2, 0.2], hi: [0.4, 0.4], material: jelly, packing_fraction: 0.6}\n")),
      doctest::Contains("bodies[0].packing_fraction"), InputError);
}
