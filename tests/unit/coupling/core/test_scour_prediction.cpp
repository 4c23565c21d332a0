// Scour predictions below a pipeline and around a pile (Sumer & Fredsoe) against hand
// evaluations for the flagship's flumes, and the exponential fit recovering a known history.
#include <coupling/scour_prediction.h>

#include <mpm/core/error.h>

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace coupling;

namespace {
//! |a - b| <= tol |b|.
bool near(double a, double b, double tol) { return std::abs(a - b) <= tol * std::abs(b); }

//! A prediction against hand values: U_f and theta to 1e-4, S_eq exactly, T to `tol`.
void check_prediction(const ScourPrediction& p, double friction_velocity, double shields, double depth,
                      double time_scale, double tol) {
  CHECK(near(p.friction_velocity, friction_velocity, 1e-4));
  CHECK(near(p.shields_number, shields, 1e-4));
  CHECK(near(p.scour_depth, depth, 1e-12));
  CHECK(near(p.time_scale, time_scale, tol));
}
}  // namespace

TEST_CASE("pipeline scour: Shields number, equilibrium depth and time scale of the flagship's flume") {
  // D = 5 cm, U = 0.4 m/s over h = 0.15 m, d = 0.5 mm quartz (s = 2.65). By hand:
  // U_f = 0.4 / (2.5 ln(11 * 0.15 / 0.00125)) = 0.022268 m/s, theta = U_f^2 / (9.81 * 1.65 * 5e-4)
  // = 0.061269, T* = theta^(-5/3) / 50 = 2.1006, T = T* D^2 / sqrt(9.81 * 1.65 * 5e-4^3) = 116.75 s.
  const ScourCurrent flume{0.4, 0.15, 5e-4, 2.65, 9.81};
  const ScourPrediction p = predict_pipeline_scour(0.05, flume);
  check_prediction(p, 0.022268, 0.061269, 0.03, 116.75, 1e-3);
  // A faster current scours sooner: T falls as theta^(-5/3).
  ScourCurrent fast = flume;
  fast.speed = 0.8;
  CHECK(near(predict_pipeline_scour(0.05, fast).time_scale, p.time_scale * std::pow(4.0, -5.0 / 3.0), 1e-9));

  ScourCurrent shallow = flume, light = flume;
  shallow.depth = 1e-5;
  light.relative_density = 1.0;
  CHECK_THROWS_AS(predict_pipeline_scour(0.05, shallow), mpm::InputError);
  CHECK_THROWS_AS(predict_pipeline_scour(0.05, light), mpm::InputError);
  CHECK_THROWS_AS(predict_pipeline_scour(0.0, flume), mpm::InputError);
}

TEST_CASE("pile scour: equilibrium depth and time scale of the 3D flagship's flume") {
  // D = 6 cm, U = 0.4 m/s over h = 0.12 m, d = 0.5 mm quartz. By hand:
  // U_f = 0.4 / (2.5 ln(11 * 0.12 / 0.00125)) = 0.022981 m/s, theta = 0.065256,
  // T* = (h / D) theta^(-2.2) / 2000 = 0.40536, T = T* D^2 / sqrt(9.81 * 1.65 * 5e-4^3) = 32.442 s.
  const ScourCurrent flume{0.4, 0.12, 5e-4, 2.65, 9.81};
  const ScourPrediction p = predict_pile_scour(0.06, flume);
  check_prediction(p, 0.022981, 0.065256, 0.078, 32.442, 1e-4);
  // T grows with the depth (the boundary layer) and falls as theta^(-2.2).
  ScourCurrent deep = flume, fast = flume;
  deep.depth = 0.24;
  fast.speed = 0.8;
  const ScourPrediction d = predict_pile_scour(0.06, deep);
  CHECK(near(d.time_scale, 2.0 * p.time_scale * std::pow(d.shields_number / p.shields_number, -2.2), 1e-9));
  CHECK(near(predict_pile_scour(0.06, fast).time_scale, p.time_scale * std::pow(4.0, -2.2), 1e-9));
  CHECK_THROWS_AS(predict_pile_scour(-0.06, flume), mpm::InputError);
  ScourCurrent still = flume;
  still.speed = 0.0;
  CHECK_THROWS_AS(predict_pile_scour(0.06, still), mpm::InputError);
}

TEST_CASE("scour fit: recovers S_eq and T of an exponential history, and a history far from equilibrium") {
  std::vector<double> t, s;
  for (int i = 0; i <= 100; ++i) {
    t.push_back(i);
    s.push_back(0.03 * (1.0 - std::exp(-i / 40.0)));
  }
  const ScourFit fit = fit_scour_history(t, s);
  CHECK(fit.equilibrium_depth == doctest::Approx(0.03).epsilon(1e-6));
  CHECK(fit.time_scale == doctest::Approx(40.0).epsilon(1e-6));
  CHECK(fit.rms_error < 1e-9);
  // Only the first 2 % of the time scale: the fit still finds it (the curvature is there).
  std::vector<double> early_s;
  for (double ti : t) early_s.push_back(0.03 * (1.0 - std::exp(-ti / 5000.0)));
  const ScourFit early = fit_scour_history(t, early_s);
  CHECK(early.time_scale == doctest::Approx(5000.0).epsilon(1e-3));
  CHECK_THROWS_AS(fit_scour_history({0.0, 1.0}, {0.0, 0.01}), mpm::InputError);
}

TEST_CASE("scour history error: 0 on the predicted history, the offset over S_eq off it") {
  ScourPrediction p;
  p.scour_depth = 0.03;
  p.time_scale = 100.0;
  std::vector<double> t, on, above;
  for (int i = 0; i <= 20; ++i) {
    t.push_back(i);
    on.push_back(0.03 * (1.0 - std::exp(-i / 100.0)));
    above.push_back(on.back() + 0.006);
  }
  CHECK(scour_history_error(t, on, p) < 1e-15);
  CHECK(scour_history_error(t, above, p) == doctest::Approx(0.2).epsilon(1e-12));
  // The t = 0 sample does not count (a history that starts from its own offset).
  above[0] = 1.0;
  CHECK(scour_history_error(t, above, p) == doctest::Approx(0.2).epsilon(1e-12));
  CHECK_THROWS_AS(scour_history_error({0.0}, {0.0}, p), mpm::InputError);
}
