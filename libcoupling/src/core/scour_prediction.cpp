// Scour predictions for a pipeline and a pile, and the exponential fit (scour_prediction.h).
#include <coupling/scour_prediction.h>

#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace coupling {

namespace {
//! g (s - 1) [m/s^2].
double reduced_gravity(const ScourCurrent& c) { return c.gravity * (c.relative_density - 1.0); }

//! T = T* D^2 / sqrt(g (s - 1) d^3) [s].
double time_scale(double t_star, double diameter, const ScourCurrent& c) {
  return t_star * diameter * diameter / std::sqrt(reduced_gravity(c) * std::pow(c.grain_diameter, 3));
}

//! The current's friction velocity and Shields number after checking the obstacle's diameter and
//! the current; `what` names the obstacle in errors.
ScourPrediction undisturbed_current(const char* what, double diameter, const ScourCurrent& c) {
  const std::string name = what;
  const double roughness = 2.5 * c.grain_diameter;
  mpm::verify<mpm::InputError>(diameter > 0.0 && c.speed > 0.0 && c.grain_diameter > 0.0 && c.gravity > 0.0,
                               name + ": diameter, current speed, grain diameter and gravity must be > 0");
  mpm::verify<mpm::InputError>(11.0 * c.depth > roughness, name + ": water depth " + std::to_string(c.depth) +
                                                               " m is not above the roughness height k_s / 11 = " +
                                                               std::to_string(roughness / 11.0) + " m of the log law");
  mpm::verify<mpm::InputError>(c.relative_density > 1.0,
                               name + ": relative density " + std::to_string(c.relative_density) + " must be > 1");
  ScourPrediction p;
  p.friction_velocity = c.speed / (2.5 * std::log(11.0 * c.depth / roughness));
  p.shields_number = p.friction_velocity * p.friction_velocity / (reduced_gravity(c) * c.grain_diameter);
  return p;
}
}  // namespace

ScourPrediction predict_pipeline_scour(double pipe_diameter, const ScourCurrent& current) {
  ScourPrediction p = undisturbed_current("pipeline scour", pipe_diameter, current);
  p.scour_depth = 0.6 * pipe_diameter;
  p.time_scale = time_scale(std::pow(p.shields_number, -5.0 / 3.0) / 50.0, pipe_diameter, current);
  return p;
}

ScourPrediction predict_pile_scour(double pile_diameter, const ScourCurrent& current) {
  ScourPrediction p = undisturbed_current("pile scour", pile_diameter, current);
  p.scour_depth = 1.3 * pile_diameter;
  p.time_scale =
      time_scale(current.depth / pile_diameter * std::pow(p.shields_number, -2.2) / 2000.0, pile_diameter, current);
  return p;
}

namespace {
//! The best S_eq for a given T and the residual sum of squares.
std::pair<double, double> fit_at(const std::vector<double>& t, const std::vector<double>& s, double time_scale) {
  double fs = 0.0, ff = 0.0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double f = 1.0 - std::exp(-t[i] / time_scale);
    fs += f * s[i];
    ff += f * f;
  }
  const double depth = ff > 0.0 ? fs / ff : 0.0;
  double rss = 0.0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double r = depth * (1.0 - std::exp(-t[i] / time_scale)) - s[i];
    rss += r * r;
  }
  return {depth, rss};
}
}  // namespace

ScourFit fit_scour_history(const std::vector<double>& time, const std::vector<double>& depth) {
  mpm::verify<mpm::InputError>(time.size() == depth.size(), "scour fit: as many times as depths are needed");
  const auto later = std::count_if(time.begin(), time.end(), [](double t) { return t > 0.0; });
  mpm::verify<mpm::InputError>(later >= 2, "scour fit: at least two samples after t = 0 are needed");
  const double t_end = *std::max_element(time.begin(), time.end());
  // Coarse logarithmic search, then golden section in log T around the best grid point.
  const int n = 241;
  const double lo = std::log(1e-3 * t_end), hi = std::log(1e3 * t_end), step = (hi - lo) / (n - 1);
  int best = 0;
  double best_rss = fit_at(time, depth, std::exp(lo)).second;
  for (int k = 1; k < n; ++k)
    if (const double rss = fit_at(time, depth, std::exp(lo + k * step)).second; rss < best_rss) {
      best_rss = rss;
      best = k;
    }
  double a = lo + std::max(best - 1, 0) * step, b = lo + std::min(best + 1, n - 1) * step;
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double c = b - ratio * (b - a), d = a + ratio * (b - a);
    if (fit_at(time, depth, std::exp(c)).second < fit_at(time, depth, std::exp(d)).second)
      b = d;
    else
      a = c;
  }
  ScourFit fit;
  fit.time_scale = std::exp(0.5 * (a + b));
  const auto [s_eq, rss] = fit_at(time, depth, fit.time_scale);
  fit.equilibrium_depth = s_eq;
  fit.rms_error = std::sqrt(rss / static_cast<double>(time.size()));
  return fit;
}

double scour_history_error(const std::vector<double>& time, const std::vector<double>& depth,
                           const ScourPrediction& prediction) {
  mpm::verify<mpm::InputError>(
      time.size() == depth.size() && prediction.scour_depth > 0.0 && prediction.time_scale > 0.0,
      "scour history error: one depth per time and a positive prediction");
  double sum = 0.0;
  int samples = 0;
  for (std::size_t i = 0; i < time.size(); ++i) {
    if (!(time[i] > 0.0)) continue;
    const double predicted = prediction.scour_depth * (1.0 - std::exp(-time[i] / prediction.time_scale));
    sum += (depth[i] - predicted) * (depth[i] - predicted);
    ++samples;
  }
  mpm::verify<mpm::InputError>(samples > 0, "scour history error: no sample after t = 0");
  return std::sqrt(sum / samples) / prediction.scour_depth;
}

}  // namespace coupling
