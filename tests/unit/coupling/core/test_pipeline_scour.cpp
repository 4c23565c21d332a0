// Pipeline scour predictions (Sumer & Fredsoe) against a hand evaluation for the flagship's
// flume, and the exponential fit recovering a known scour history.
#include <coupling/pipeline_scour.h>

#include <mpm/core/error.h>

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace coupling;

TEST_CASE("pipeline scour: Shields number, equilibrium depth and time scale of the flagship's flume") {
  // D = 5 cm, U = 0.4 m/s over h = 0.15 m, d = 0.5 mm quartz (s = 2.65). By hand:
  // U_f = 0.4 / (2.5 ln(11 * 0.15 / 0.00125)) = 0.022268 m/s, theta = U_f^2 / (9.81 * 1.65 * 5e-4)
  // = 0.061269, T* = theta^(-5/3) / 50 = 2.1006, T = T* D^2 / sqrt(9.81 * 1.65 * 5e-4^3) = 116.75 s.
  const PipelineScourPrediction p = predict_pipeline_scour(0.05, 0.4, 0.15, 5e-4, 2.65, 9.81);
  CHECK(p.friction_velocity == doctest::Approx(0.022268).epsilon(1e-4));
  CHECK(p.shields_number == doctest::Approx(0.061269).epsilon(1e-4));
  CHECK(p.scour_depth == doctest::Approx(0.03));
  CHECK(p.time_scale == doctest::Approx(116.75).epsilon(1e-3));
  // A faster current scours sooner: T falls as theta^(-5/3).
  const PipelineScourPrediction fast = predict_pipeline_scour(0.05, 0.8, 0.15, 5e-4, 2.65, 9.81);
  CHECK(fast.time_scale == doctest::Approx(p.time_scale * std::pow(4.0, -5.0 / 3.0)).epsilon(1e-9));

  CHECK_THROWS_AS(predict_pipeline_scour(0.05, 0.4, 1e-5, 5e-4, 2.65, 9.81), mpm::InputError);
  CHECK_THROWS_AS(predict_pipeline_scour(0.05, 0.4, 0.15, 5e-4, 1.0, 9.81), mpm::InputError);
  CHECK_THROWS_AS(predict_pipeline_scour(0.0, 0.4, 0.15, 5e-4, 2.65, 9.81), mpm::InputError);
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
  PipelineScourPrediction p;
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
