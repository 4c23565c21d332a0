// Constitutive models, return maps and the SVD under them.
//
// One generic test runs over every alternative of constitutive::ElasticModel in 2D and 3D
// (adding a model to the variant adds it here): P = dpsi/dF and dP by central differences,
// the rest state, rotation invariance. The return maps are checked the same way: a projected
// state lies on the yield surface, projecting twice changes nothing, admissible states are left
// alone; then the Drucker-Prager volume correction and cohesion on their own.
#include <doctest/doctest.h>

#include <mpm/constitutive/elastic_model.h>
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/core/stages/grid_boundary.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/core/stages/time_step_control.h>
#include <mpm/math/svd.h>
#include <mpm/plasticity/plasticity_model.h>
#include <mpm/solid/material.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>
#include <mpm/solid/stages/return_map.h>
#include <mpm/solid/stages/stress_forces.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

using namespace mpm;

namespace {

template <class Model>
struct DimOf;
template <template <int> class Model, int dim>
struct DimOf<Model<dim>> {
  static constexpr int value = dim;
};

template <class Variant>
struct AsTuple;
template <class... Types>
struct AsTuple<std::variant<Types...>> {
  using type = std::tuple<Types...>;
};

using AllElasticModels = decltype(std::tuple_cat(std::declval<AsTuple<constitutive::ElasticModel<2>>::type>(),
                                                 std::declval<AsTuple<constitutive::ElasticModel<3>>::type>()));

const constitutive::Lame kLame = constitutive::Lame::from_youngs_poisson(1e6, 0.3);

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

// Rotations built without the SVD under test.
template <int dim>
Mat<dim> random_rotation(std::mt19937& rng) {
  const double angle = uniform(rng, -std::numbers::pi, std::numbers::pi);
  if constexpr (dim == 2) {
    return Eigen::Rotation2Dd(angle).toRotationMatrix();
  } else {
    const Vec<3> axis = Vec<3>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); }).normalized();
    return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  }
}

template <int dim>
Mat<dim> random_matrix(std::mt19937& rng) {
  return Mat<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); });
}

// R1 diag(stretch) R2 with random rotations.
template <int dim>
Mat<dim> with_stretches(std::mt19937& rng, const Vec<dim>& stretch) {
  return random_rotation<dim>(rng) * stretch.asDiagonal() * random_rotation<dim>(rng);
}

template <int dim>
Vec<dim> random_stretches(std::mt19937& rng, double lo, double hi) {
  return Vec<dim>::NullaryExpr([&] { return uniform(rng, lo, hi); });
}

template <class Model, int dim>
Mat<dim> finite_difference_gradient(const Model& model, const Mat<dim>& F, double h) {
  Mat<dim> P;
  for (int i = 0; i < dim; ++i) {
    for (int j = 0; j < dim; ++j) {
      Mat<dim> E = Mat<dim>::Zero();
      E(i, j) = h;
      P(i, j) = (model.energy(F + E) - model.energy(F - E)) / (2 * h);
    }
  }
  return P;
}

double relative_error(const auto& approx, const auto& exact) { return (approx - exact).norm() / exact.norm(); }

}  // namespace

TEST_CASE_TEMPLATE_DEFINE("elastic model: P = dpsi/dF, dP, rest state, rotation invariance", Model, elastic_models) {
  constexpr int dim = DimOf<Model>::value;
  INFO(std::string(Model::name), " in ", dim, "D");
  const Model model{kLame.mu, kLame.lambda};
  const double stress_scale = kLame.p_wave_modulus();
  std::mt19937 rng(20170);

  CHECK(std::abs(model.energy(Mat<dim>::Identity())) <= 1e-12 * stress_scale);
  CHECK(model.first_piola(Mat<dim>::Identity()).norm() <= 1e-12 * stress_scale);

  std::vector<Mat<dim>> samples;
  for (int n = 0; n < 6; ++n) samples.push_back(with_stretches<dim>(rng, random_stretches<dim>(rng, 0.6, 1.5)));
  // Repeated singular values: the divided differences of the differential meet 0/0.
  Vec<dim> repeated = Vec<dim>::Constant(1.2);
  repeated(dim - 1) = 0.8;
  samples.push_back(with_stretches<dim>(rng, repeated));
  samples.push_back(random_rotation<dim>(rng) * 1.1);
  // Inverted F: a negative singular value, in every model (inversion handling).
  for (int n = 0; n < 3; ++n) {
    Vec<dim> stretch = random_stretches<dim>(rng, 0.9, 1.5);
    stretch(dim - 1) = -uniform(rng, 0.4, 0.6);
    samples.push_back(with_stretches<dim>(rng, stretch));
  }
  // Below the critical stretch of the logarithmic models, and flat (sigma = 0).
  for (const double flat : {0.05, 0.0}) {
    Vec<dim> stretch = random_stretches<dim>(rng, 0.9, 1.5);
    stretch(dim - 1) = flat;
    samples.push_back(with_stretches<dim>(rng, stretch));
  }
  for (const Mat<dim>& F : samples) {
    CAPTURE(F);
    const Mat<dim> P = model.first_piola(F);
    CHECK(relative_error(finite_difference_gradient(model, F, 1e-6), P) < 1e-6);

    const Mat<dim> dF = random_matrix<dim>(rng);
    const double h = 1e-6;
    const Mat<dim> dP_fd = (model.first_piola(F + h * dF) - model.first_piola(F - h * dF)) / (2 * h);
    CHECK(relative_error(dP_fd, model.first_piola_differential(F, dF)) < 1e-6);

    const Mat<dim> R = random_rotation<dim>(rng);
    CHECK(model.energy(R * F) == doctest::Approx(model.energy(F)).epsilon(1e-11));
    CHECK(relative_error(model.first_piola(R * F), R * P) < 1e-11);
  }
}
TEST_CASE_TEMPLATE_APPLY(elastic_models, AllElasticModels);

TEST_CASE_TEMPLATE_DEFINE("elastic model: flat and inverted particles are pushed back", Model, restoring_models) {
  constexpr int dim = DimOf<Model>::value;
  INFO(std::string(Model::name), " in ", dim, "D");
  const Model model{kLame.mu, kLame.lambda};
  for (const double last : {0.0, -0.3, -1.0}) {
    Vec<dim> stretch = Vec<dim>::Constant(1.1);
    stretch(dim - 1) = last;
    const Mat<dim> F = stretch.asDiagonal();
    const Mat<dim> P = model.first_piola(F);
    CAPTURE(F);
    REQUIRE(P.allFinite());
    // -P is the force on F: it must raise the negative or zero singular value (dJ > 0 along
    // d sigma_last), i.e. the energy falls as sigma_last grows.
    CHECK(P(dim - 1, dim - 1) < 0.0);
    CHECK(std::isfinite(model.energy(F)));
  }
}
TEST_CASE_TEMPLATE_APPLY(restoring_models, AllElasticModels);

TEST_CASE_TEMPLATE_DEFINE("stress derivative: definiteness fix (Teran et al. 2005)", Model, definite_models) {
  constexpr int dim = DimOf<Model>::value;
  INFO(std::string(Model::name), " in ", dim, "D");
  const Model model{kLame.mu, kLame.lambda};
  std::mt19937 rng(2005);
  const auto quadratic_form = [](const constitutive::StressDerivative<dim>& d, const Mat<dim>& dF) {
    return (d.apply(dF).array() * dF.array()).sum();
  };
  // Stretched a little in every direction the model is convex (under compression the
  // rotational modes soften: (p_i + p_j)/(sigma_i + sigma_j) < 0): the fix changes nothing.
  for (int n = 0; n < 4; ++n) {
    const Mat<dim> F = with_stretches<dim>(rng, random_stretches<dim>(rng, 1.0, 1.03));
    const auto exact = constitutive::stress_derivative(model, F, false);
    const auto fixed = constitutive::stress_derivative(model, F, true);
    for (int k = 0; k < 4; ++k) {
      const Mat<dim> dF = random_matrix<dim>(rng);
      CHECK(relative_error(fixed.apply(dF), exact.apply(dF)) < 1e-12);
    }
  }
  // Compressed, stretched and inverted states: the fixed differential is positive
  // semi-definite and symmetric in the Frobenius product; the exact one is not always.
  for (int n = 0; n < 20; ++n) {
    Vec<dim> stretch = random_stretches<dim>(rng, 0.2, 2.5);
    if (n % 3 == 0) stretch(dim - 1) = -uniform(rng, 0.05, 0.8);
    const Mat<dim> F = with_stretches<dim>(rng, stretch);
    const auto fixed = constitutive::stress_derivative(model, F, true);
    for (int k = 0; k < 8; ++k) {
      const Mat<dim> A = random_matrix<dim>(rng), B = random_matrix<dim>(rng);
      CHECK(quadratic_form(fixed, A) >= -1e-9 * kLame.p_wave_modulus() * A.squaredNorm());
      const double ab = (fixed.apply(A).array() * B.array()).sum(), ba = (fixed.apply(B).array() * A.array()).sum();
      CHECK(ab == doctest::Approx(ba).epsilon(1e-9).scale(kLame.p_wave_modulus()));
    }
  }
}
TEST_CASE_TEMPLATE_APPLY(definite_models, AllElasticModels);

TEST_CASE_TEMPLATE("rotation-variant SVD and polar decomposition", Matrix, Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  std::mt19937 rng(42);
  std::vector<Mat<dim>> samples = {Mat<dim>::Identity(), -Mat<dim>::Identity(), Mat<dim>::Zero(),
                                   2.0 * Mat<dim>::Identity(), random_rotation<dim>(rng)};
  Mat<dim> rank_one = random_matrix<dim>(rng).col(0) * random_matrix<dim>(rng).row(0);
  samples.push_back(rank_one);
  Mat<dim> reflection = Mat<dim>::Identity();
  reflection(0, 0) = -1;
  samples.push_back(random_rotation<dim>(rng) * reflection);
  samples.push_back(random_rotation<dim>(rng) * Vec<dim>::Constant(1e-9).asDiagonal());
  for (int n = 0; n < 20; ++n) samples.push_back(random_matrix<dim>(rng));

  for (const Mat<dim>& F : samples) {
    CAPTURE(F);
    const math::Svd<dim> f = math::svd(F);
    CHECK((f.U * f.sigma.asDiagonal() * f.V.transpose() - F).norm() <= 1e-14 * F.norm());
    CHECK((f.U.transpose() * f.U - Mat<dim>::Identity()).norm() < 1e-14);
    CHECK((f.V.transpose() * f.V - Mat<dim>::Identity()).norm() < 1e-14);
    CHECK(f.U.determinant() == doctest::Approx(1.0));
    CHECK(f.V.determinant() == doctest::Approx(1.0));
    for (int i = 0; i + 1 < dim; ++i) {
      CHECK(f.sigma(i) >= 0.0);
      CHECK(f.sigma(i) >= std::abs(f.sigma(i + 1)));
    }
    if (std::abs(F.determinant()) > 1e-12) CHECK((f.sigma(dim - 1) < 0) == (F.determinant() < 0));

    const math::Polar<dim> p = math::polar(F);
    CHECK((p.R * p.S - F).norm() <= 1e-14 * F.norm());
    CHECK((p.R.transpose() * p.R - Mat<dim>::Identity()).norm() < 1e-14);
    CHECK(p.R.determinant() == doctest::Approx(1.0));
    CHECK((p.S - p.S.transpose()).norm() <= 1e-14 * F.norm());
  }
}

namespace {

// Return maps under test, each in a few parameter sets.
template <class Model>
std::vector<Model> return_maps();
template <>
std::vector<plasticity::DruckerPrager<2>> return_maps() {
  return {{30.0, 0.0, kLame}, {40.0, 2e4, kLame}, {0.0, 1e4, kLame}};
}
template <>
std::vector<plasticity::DruckerPrager<3>> return_maps() {
  return {{30.0, 0.0, kLame}, {40.0, 2e4, kLame}, {0.0, 1e4, kLame}};
}
template <>
std::vector<plasticity::VonMises<2>> return_maps() {
  return {{2e4, kLame}};
}
template <>
std::vector<plasticity::VonMises<3>> return_maps() {
  return {{2e4, kLame}};
}
template <>
std::vector<plasticity::Snow<2>> return_maps() {
  return {{2.5e-2, 7.5e-3, 10.0}};
}
template <>
std::vector<plasticity::Snow<3>> return_maps() {
  return {{2.5e-2, 7.5e-3, 10.0}};
}

}  // namespace

TEST_CASE_TEMPLATE("return map: lands on the yield surface, idempotent, admissible states untouched", Model,
                   plasticity::DruckerPrager<2>, plasticity::DruckerPrager<3>, plasticity::VonMises<2>,
                   plasticity::VonMises<3>, plasticity::Snow<2>, plasticity::Snow<3>) {
  constexpr int dim = DimOf<Model>::value;
  const constitutive::HenckyStVK<dim> elastic{kLame.mu, kLame.lambda};
  std::mt19937 rng(2016);
  // The SVD a projection hands out (for the stress cache, stages::ReturnMap) is that of the F^E
  // it leaves, and the Kirchhoff stress from it is tau(F^E).
  const auto check_result_svd = [&](const Model& model, const Mat<dim>& trial, const Mat<dim>& Fe) {
    Mat<dim> again = trial;
    double plastic = 0.0;
    math::Svd<dim> f;
    model.project(again, plastic, &f);
    CHECK(again == Fe);
    CHECK((f.U * f.sigma.asDiagonal() * f.V.transpose() - Fe).norm() <= 1e-13 * Fe.norm());
    const Mat<dim> tau = elastic.first_piola(Fe) * Fe.transpose();
    CHECK((constitutive::isotropic_kirchhoff(elastic, f) - tau).norm() <= 1e-12 * kLame.mu);
    // The Hencky-strain maps also hand out log sigma of the F^E they leave, and the Hencky
    // stress from it (without logarithms) is tau(F^E) as well.
    if constexpr (!std::is_same_v<Model, plasticity::Snow<dim>>) {
      Mat<dim> third = trial;
      double third_plastic = 0.0;
      math::Svd<dim> g;
      Vec<dim> log_sigma = Vec<dim>::Constant(std::nan(""));
      if constexpr (std::is_same_v<Model, plasticity::DruckerPrager<dim>>)
        model.project(third, math::svd(trial), third_plastic, nullptr, 0.0, &g, &log_sigma);
      else
        model.project(third, math::svd(trial), third_plastic, &g, &log_sigma);
      CHECK(third == Fe);
      CHECK((log_sigma - g.sigma.array().log().matrix()).cwiseAbs().maxCoeff() <= 1e-14);
      CHECK((elastic.kirchhoff(g, log_sigma) - tau).norm() <= 1e-12 * kLame.mu);
    }
  };
  for (const Model& model : return_maps<Model>()) {
    int outside = 0, inside = 0;
    for (int n = 0; n < 200; ++n) {
      // Every other trial is mildly compressed with little shear, mostly admissible.
      const Vec<dim> stretch = n % 2 ? random_stretches<dim>(rng, 0.97, 0.995) : random_stretches<dim>(rng, 0.9, 1.1);
      const Mat<dim> trial = with_stretches<dim>(rng, stretch);
      CAPTURE(trial);
      Mat<dim> Fe = trial;
      double plastic = 0.0;
      if (model.yield_function(trial) <= 0.0) {
        check_result_svd(model, trial, trial);
        ++inside;
        CHECK_FALSE(model.project(Fe, plastic));
        CHECK(Fe == trial);
        CHECK(plastic == 0.0);
        continue;
      }
      ++outside;
      const double stress_scale = (elastic.first_piola(trial) * trial.transpose()).norm();
      REQUIRE(model.project(Fe, plastic));
      CHECK(std::abs(model.yield_function(Fe)) <= 1e-10 * stress_scale);
      CHECK(Fe.determinant() > 0.0);
      check_result_svd(model, trial, Fe);

      Mat<dim> again = Fe;
      double plastic_again = plastic;
      model.project(again, plastic_again);
      CHECK((again - Fe).norm() <= 1e-12 * Fe.norm());
      CHECK(plastic_again == doctest::Approx(plastic).epsilon(1e-12));
    }
    CHECK(outside > 20);
    CHECK(inside > 20);
  }
}

TEST_CASE_TEMPLATE("Hencky stress from the log stretches: without logarithms above the clamp, the same below", Matrix,
                   Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const constitutive::HenckyStVK<dim> elastic{kLame.mu, kLame.lambda};
  std::mt19937 rng(7);
  for (int n = 0; n < 50; ++n) {
    // Stretched and compressed states, and every fifth with a singular value below the clamp
    // (crushed), flat or inverted, where the extended logarithm differs from log|sigma|.
    Vec<dim> stretch = random_stretches<dim>(rng, 0.5, 1.5);
    if (n % 5 == 0) stretch(dim - 1) = (n % 3 - 1) * 0.05;
    const Mat<dim> F = with_stretches<dim>(rng, stretch);
    const math::Svd<dim> f = math::svd(F);
    const Vec<dim> log_sigma = constitutive::HenckyStVK<dim>::principal_strain(f.sigma);
    CAPTURE(f.sigma.transpose());
    if (f.sigma.minCoeff() < constitutive::inversion_clamp)
      CHECK(elastic.kirchhoff(f, log_sigma) == constitutive::isotropic_kirchhoff(elastic, f));
    else
      CHECK((elastic.kirchhoff(f, log_sigma) - constitutive::isotropic_kirchhoff(elastic, f)).norm() <=
            1e-14 * (kLame.mu + kLame.lambda));
  }
}

TEST_CASE_TEMPLATE("snow: the clamp keeps det F^E J^P, compaction hardens, stretching softens", Matrix, Mat<2>,
                   Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::Snow<dim> snow(2.5e-2, 7.5e-3, 10.0);
  std::mt19937 rng(2013);
  double plastic = 0.0;
  Mat<dim> Fe = Mat<dim>::Identity();
  // Compaction in steps, as a particle under load: F = product of the steps.
  double J = 1.0;
  for (int n = 0; n < 10; ++n) {
    const Mat<dim> step = with_stretches<dim>(rng, random_stretches<dim>(rng, 0.95, 1.0));
    J *= step.determinant();
    Fe = step * Fe;
    snow.project(Fe, plastic);
    CHECK(Fe.determinant() * std::exp(plastic) == doctest::Approx(J).epsilon(1e-12));
    CHECK(snow.yield_function(Fe) <= 1e-14);
  }
  CHECK(plastic < 0.0);                      // J^P < 1: compacted
  CHECK(snow.modulus_scale(plastic) > 1.0);  // harder
  CHECK(snow.modulus_scale(0.0) == 1.0);
  CHECK(snow.modulus_scale(std::log(1.1)) == doctest::Approx(std::exp(-1.0)));  // xi (1 - J^P) = -1
}

TEST_CASE_TEMPLATE("von Mises flow is isochoric", Matrix, Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::VonMises<dim> model(2e4, kLame);
  std::mt19937 rng(3);
  Vec<dim> stretch = Vec<dim>::Constant(1.0);
  stretch(0) = 1.3;
  Mat<dim> Fe = with_stretches<dim>(rng, stretch);
  const double J = Fe.determinant();
  double plastic = 0.0;
  REQUIRE(model.project(Fe, plastic));
  CHECK(Fe.determinant() == doctest::Approx(J).epsilon(1e-13));
  CHECK(plastic == 0.0);
}

TEST_CASE_TEMPLATE("Drucker-Prager volume correction: no volume gain", Matrix, Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const plasticity::DruckerPrager<dim> sand(30.0, 0.0, kLame);

  // Expand by 2 % per step for 10 steps, then compress back. Each expansion step is projected
  // to the apex (stress free); with the correction the material is back at its original volume
  // and stress free, without it the elastic state ends compressed by 1.02^-10 per axis and
  // would push the material out to the expanded volume.
  const auto expand_and_return = [&](bool correct) {
    Mat<dim> Fe = Mat<dim>::Identity();
    double plastic = 0.0;
    for (int step = 0; step < 20; ++step) {
      Fe *= step < 10 ? 1.02 : 1.0 / 1.02;
      if (!correct) plastic = 0.0;
      sand.project(Fe, plastic);
    }
    return Fe;
  };
  const Mat<dim> corrected = expand_and_return(true);
  CHECK((corrected - Mat<dim>::Identity()).norm() < 1e-12);
  CHECK(expand_and_return(false).determinant() == doctest::Approx(std::pow(1.02, -10 * dim)));

  // In general: log det Fe + plastic is the log of the total volume change, for any sequence
  // of dilations, compressions and shears, with or without cohesion.
  std::mt19937 rng(17);
  for (const auto& model : {sand, plasticity::DruckerPrager<dim>(35.0, 5e3, kLame)}) {
    Mat<dim> Fe = Mat<dim>::Identity();
    double plastic = 0.0;
    double log_J_total = 0.0;
    for (int step = 0; step < 100; ++step) {
      const Mat<dim> increment = with_stretches<dim>(rng, random_stretches<dim>(rng, 0.97, 1.03));
      log_J_total += std::log(increment.determinant());
      Fe = increment * Fe;
      model.project(Fe, plastic);
      CHECK(plastic >= 0.0);
      CHECK(std::log(Fe.determinant()) + plastic == doctest::Approx(log_J_total).scale(1.0).epsilon(1e-12));
    }
  }
}

TEST_CASE_TEMPLATE("Drucker-Prager cohesion moves the apex to tr tau = 3 c cot(phi)", Matrix, Mat<2>, Mat<3>) {
  constexpr int dim = Matrix::RowsAtCompileTime;
  const double phi = 35.0, cohesion = 5e3;
  const plasticity::DruckerPrager<dim> cohesive(phi, cohesion, kLame);
  const plasticity::DruckerPrager<dim> dry(phi, 0.0, kLame);
  const constitutive::HenckyStVK<dim> elastic{kLame.mu, kLame.lambda};
  const auto trace_tau = [&](const Mat<dim>& F) { return (elastic.first_piola(F) * F.transpose()).trace(); };
  const double apex = 3.0 * cohesion / std::tan(phi * std::numbers::pi / 180.0);

  // Far beyond the apex in tension: both project to their apex.
  Mat<dim> Fe = 1.2 * Mat<dim>::Identity();
  double plastic = 0.0;
  REQUIRE(cohesive.project(Fe, plastic));
  CHECK(trace_tau(Fe) == doctest::Approx(apex).epsilon(1e-10));
  CHECK(cohesive.yield_function(Fe) == doctest::Approx(0.0).scale(apex).epsilon(1e-12));
  Fe = 1.2 * Mat<dim>::Identity();
  plastic = 0.0;
  REQUIRE(dry.project(Fe, plastic));
  CHECK((Fe - Mat<dim>::Identity()).norm() < 1e-14);

  // A hydrostatic tension below the cohesive apex: admissible only with cohesion.
  const double log_stretch = 0.5 * apex / (dim * (dim * kLame.lambda + 2 * kLame.mu));
  const Mat<dim> tension = std::exp(log_stretch) * Mat<dim>::Identity();
  CHECK(trace_tau(tension) == doctest::Approx(0.5 * apex));
  Fe = tension;
  plastic = 0.0;
  CHECK_FALSE(cohesive.project(Fe, plastic));
  CHECK(dry.project(Fe, plastic));
}

TEST_CASE("parse_material: models, moduli, wave speed and rejected pairings") {
  const Config sand = Config::parse(R"(
name: sand
density: 1600
youngs_modulus: 1.0e6
poisson_ratio: 0.3
elasticity: hencky_stvk
plasticity:
  model: drucker_prager
  friction_angle: 35
  cohesion: 100
)");
  const Material<3> m = parse_material<3>(sand);
  CHECK(m.name == "sand");
  CHECK(std::holds_alternative<constitutive::HenckyStVK<3>>(m.elastic));
  CHECK(std::holds_alternative<plasticity::DruckerPrager<3>>(m.plasticity));
  CHECK(m.lame.mu == doctest::Approx(kLame.mu));
  CHECK(m.lame.lambda == doctest::Approx(kLame.lambda));
  CHECK(m.wave_speed() == doctest::Approx(std::sqrt((kLame.lambda + 2 * kLame.mu) / 1600)));
  const Mat<3> F = Vec<3>(1.1, 0.95, 1.02).asDiagonal();
  const constitutive::HenckyStVK<3> hencky{kLame.mu, kLame.lambda};
  CHECK(m.energy(F) == doctest::Approx(hencky.energy(F)));
  CHECK(relative_error(m.kirchhoff(F), Mat<3>(hencky.first_piola(F) * F.transpose())) < 1e-14);

  const Material<2> jelly =
      parse_material<2>(Config::parse("density: 1000\nyoungs_modulus: 1e5\npoisson_ratio: 0.4\n"));
  CHECK(jelly.name == "material");
  CHECK(std::holds_alternative<constitutive::FixedCorotated<2>>(jelly.elastic));
  CHECK(std::holds_alternative<plasticity::NoPlasticity>(jelly.plasticity));

  const std::string base = "density: 1000\nyoungs_modulus: 1e5\n";
  const std::string von_mises = "plasticity: {model: von_mises, yield_stress: 1e3}\n";
  CHECK_THROWS_WITH_AS(parse_material<3>(Config::parse(base + "poisson_ratio: 0.3\n" + von_mises)),
                       doctest::Contains("hencky_stvk"), InputError);
  CHECK_THROWS_AS(parse_material<3>(Config::parse(base + "poisson_ratio: 0.5\n")), InputError);
  const std::string no_yield_stress = "elasticity: hencky_stvk\nplasticity: {model: von_mises}\n";
  CHECK_THROWS_AS(parse_material<3>(Config::parse(base + "poisson_ratio: 0.3\n" + no_yield_stress)), InputError);
}

namespace {

// The explicit step of a scene with plastic material takes the stress of the return map's SVD
// (solid_channels.h, stress cache) instead of a second SVD of F^E. A run that forgets the cache
// before every step (each stress then comes from F^E, as without the cache) must follow the
// same trajectory to round-off; the cache must hold tau(F^E) of every plastic particle and
// nothing for the elastic ones.
// The second body's material: an elastic jelly by default (no stress cache of its own).
const std::string elastic_jelly =
    "{name: jelly, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: fixed_corotated}";
// Plastic second bodies: every particle then carries a cached stress, which the p2g scatter
// reads in place (ParticleStress) with the weights V^0 (von Mises) or V^0 times the snow's
// hardening of the moduli.
const std::string hardening_snow =
    "{name: jelly, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: fixed_corotated,"
    " plasticity: {model: snow, critical_compression: 2.5e-3, critical_stretch: 7.5e-4, hardening: 10}}";
const std::string von_mises_goo =
    "{name: jelly, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk,"
    " plasticity: {model: von_mises, yield_stress: 300}}";

template <int dim>
solid::SolidScene<dim> sand_and_jelly(const std::string& jelly = elastic_jelly) {
  const std::string z = dim == 3 ? ", 0.35]" : "]", z0 = dim == 3 ? ", 0.15]" : "]", zd = dim == 3 ? ", 0]" : "]";
  return solid::load_solid_scene<dim>(Config::parse(
      "dim: " + std::to_string(dim) + "\ndomain: {lo: [0, 0" + zd + ", hi: [1, 0.5" + (dim == 3 ? ", 0.5]" : "]") +
      "}\ngrid: {dx: " + (dim == 3 ? "0.05" : "0.025") +
      "}\nwalls: {contact: sticky}\ntime: {end: 1, frame_dt: 1, cfl: 0.4}\ngravity: [0, -9.81" + zd +
      "\nmaterials:\n"
      "  - {name: sand, density: 2650, youngs_modulus: 1.0e6, poisson_ratio: 0.3, elasticity: hencky_stvk,"
      " plasticity: {model: drucker_prager, friction_angle: 30}}\n"
      "  - " +
      jelly +
      "\n"
      "bodies:\n"
      "  - {shape: box, material: sand, lo: [0.1, 0.1" +
      z0 + ", hi: [0.3, 0.4" + z + "}\n  - {shape: box, material: jelly, lo: [0.6, 0.1" + z0 + ", hi: [0.8, 0.25" + z +
      ", velocity: [0, -1" + zd + "}\n"));
}

template <int dim>
void check_stress_cache() {
  INFO("dim = ", dim);
  solid::SolidScene<dim> cached = sand_and_jelly<dim>(), recomputed = sand_and_jelly<dim>();
  REQUIRE(solid::stress_cache(cached.state.particles) != nullptr);
  Pipeline<MpmState<dim>> a = solid::make_solid_pipeline(cached), b = solid::make_solid_pipeline(recomputed);
  for (int step = 0; step < 80; ++step) {
    a.step(cached.state);
    for (Mat<dim>& tau : *solid::stress_cache(recomputed.state.particles))
      tau.setConstant(std::numeric_limits<double>::quiet_NaN());
    b.step(recomputed.state);
  }
  const Particles<dim>&P = cached.state.particles, &Q = recomputed.state.particles;
  REQUIRE(P.size() == Q.size());
  double dx = 0.0, dv = 0.0, vmax = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    dx = std::max(dx, (P.x[p] - Q.x[p]).norm());
    dv = std::max(dv, (P.v[p] - Q.v[p]).norm());
    vmax = std::max(vmax, Q.v[p].norm());
  }
  CHECK(dx <= 1e-12);
  CHECK(dv <= 1e-10 * vmax);
  CHECK(vmax > 0.1);

  const std::vector<Mat<dim>>& F = solid::elastic_F(P);
  const std::vector<Mat<dim>>& cache = *solid::stress_cache(P);
  const auto& sand = cached.materials[0];
  const double sand_mu = constitutive::Lame::from_youngs_poisson(1e6, 0.3).mu;
  int on_cone = 0, sand_particles = 0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (P.material[p] == 1) {  // jelly: elastic, no cache
      CHECK_FALSE(solid::known_stress(cache[p]));
      continue;
    }
    ++sand_particles;
    REQUIRE(solid::known_stress(cache[p]));
    const Mat<dim> tau = std::get<constitutive::HenckyStVK<dim>>(sand.elastic).first_piola(F[p]) * F[p].transpose();
    CHECK((cache[p] - tau).norm() <= 1e-12 * sand_mu);  // round-off of the moduli's scale
    if (std::get<plasticity::DruckerPrager<dim>>(sand.plasticity).yield_function(F[p]) >
        -1e-6 * std::max(tau.norm(), 1.0))
      ++on_cone;
  }
  CHECK(on_cone > sand_particles / 10);  // the return map did work
}

// Largest |a_p - b_p| over the particles, relative to the largest |b_p|.
template <class T>
double relative_difference(const std::vector<T>& a, const std::vector<T>& b) {
  double worst = 0.0, scale = 0.0;
  for (std::size_t p = 0; p < a.size(); ++p) {
    worst = std::max(worst, double((a[p] - b[p]).norm()));
    scale = std::max(scale, double(b[p].norm()));
  }
  return scale > 0.0 ? worst / scale : worst;
}

// The explicit solver's pipeline scatters the stress forces in its p2g pass and projects each
// bucket right after its gather (p2g_stress, g2p_plasticity). The same step assembled from the
// separate stages (p2g, stress_forces, g2p, plasticity) must give the same particles: bit for
// bit where p2g_stress keeps a force channel (FLIP), to round-off (`tolerance`, relative to
// each channel's largest value) where it adds the forces to the momentum as impulses (APIC).
template <int dim>
void check_fused_passes(TransferScheme::Type scheme, double tolerance, const std::string& jelly = elastic_jelly) {
  INFO("dim = ", dim, ", flip = ", scheme == TransferScheme::Type::flip, ", second body ", jelly);
  solid::SolidScene<dim> fused = sand_and_jelly<dim>(jelly), separate = sand_and_jelly<dim>(jelly);
  fused.state.transfer.type = separate.state.transfer.type = scheme;
  Pipeline<MpmState<dim>> a = solid::make_solid_pipeline(fused);
  const std::vector<std::string> names = a.stage_names();
  CHECK(std::find(names.begin(), names.end(), "p2g_stress") != names.end());
  CHECK(std::find(names.begin(), names.end(), "g2p_plasticity") != names.end());
  Pipeline<MpmState<dim>> b(particle_fields(separate.state.particles));
  b.add(std::make_unique<stages::TimeStepControl<dim>>(
      stages::time_step_settings(separate.settings, separate.solver->wave_speed())));
  b.add(std::make_unique<stages::SortParticles<dim>>());
  b.add(std::make_unique<stages::ParticlesToGrid<dim>>());
  b.add(std::make_unique<stages::StressForces<dim>>(separate.materials));
  b.add(std::make_unique<stages::GridVelocityUpdate<dim>>(true));
  b.add(std::make_unique<stages::GridBoundary<dim>>(separate.colliders));
  b.add(std::make_unique<stages::GridToParticles<dim>>(solid::kElasticF));
  b.add(std::make_unique<stages::ReturnMap<dim>>(separate.materials));
  for (int step = 0; step < 60; ++step) {
    a.step(fused.state);
    b.step(separate.state);
    CHECK(fused.state.grid.force.empty() == (scheme == TransferScheme::Type::apic));
  }
  const Particles<dim>&P = fused.state.particles, &Q = separate.state.particles;
  REQUIRE(P.size() == Q.size());
  CHECK(fused.state.time == separate.state.time);
  const std::vector<double>&ep = solid::plastic_state(P), &eq = solid::plastic_state(Q);
  double plastic = 0.0, plastic_scale = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    plastic = std::max(plastic, std::abs(ep[p] - eq[p]));
    plastic_scale = std::max(plastic_scale, std::abs(eq[p]));
  }
  if (tolerance == 0.0) {
    CHECK(P.x == Q.x);
    CHECK(P.v == Q.v);
    CHECK(P.C == Q.C);
    CHECK(solid::elastic_F(P) == solid::elastic_F(Q));
    CHECK(ep == eq);
    const std::vector<Mat<dim>>&cp = *solid::stress_cache(P), &cq = *solid::stress_cache(Q);
    for (std::size_t p = 0; p < P.size(); ++p)  // NaN (unknown) entries compare unequal
      REQUIRE((cp[p] == cq[p] || (!solid::known_stress(cp[p]) && !solid::known_stress(cq[p]))));
  } else {
    CHECK(relative_difference(P.x, Q.x) < tolerance);
    CHECK(relative_difference(P.v, Q.v) < tolerance);
    CHECK(relative_difference(P.C, Q.C) < tolerance);
    CHECK(relative_difference(solid::elastic_F(P), solid::elastic_F(Q)) < tolerance);
    CHECK(plastic <= tolerance * plastic_scale);
  }
  double vmax = 0.0;
  for (const Vec<dim>& v : P.v) vmax = std::max(vmax, v.norm());
  CHECK(vmax > 0.1);  // the bodies moved
}

}  // namespace

TEST_CASE("the explicit step's fused passes give the separate stages' particles (2D and 3D)") {
  check_fused_passes<2>(TransferScheme::Type::flip, 0.0);
  check_fused_passes<3>(TransferScheme::Type::flip, 0.0);
  // Measured after the 60 steps: 3.5e-14 (v), 6.6e-14 (C), 2.1e-13 (plastic) at most.
  check_fused_passes<2>(TransferScheme::Type::apic, 1e-10);
  check_fused_passes<3>(TransferScheme::Type::apic, 1e-10);
}

TEST_CASE(
    "all materials plastic: the fused scatter reads the stress cache, the separate stages' particles bit for "
    "bit (2D and 3D)") {
  for (const std::string& jelly : {hardening_snow, von_mises_goo}) {
    check_fused_passes<2>(TransferScheme::Type::flip, 0.0, jelly);
    check_fused_passes<3>(TransferScheme::Type::flip, 0.0, jelly);
  }
}

TEST_CASE("stress cache: one SVD per step, the same trajectory to round-off (2D and 3D)") {
  check_stress_cache<2>();
  check_stress_cache<3>();
}
