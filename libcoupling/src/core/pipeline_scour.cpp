// Pipeline scour predictions and the exponential fit (pipeline_scour.h).
#include <coupling/pipeline_scour.h>

#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace coupling {

PipelineScourPrediction predict_pipeline_scour(double pipe_diameter, double speed, double depth, double grain_diameter,
                                               double relative_density, double gravity) {
  const double roughness = 2.5 * grain_diameter;
  mpm::verify<mpm::InputError>(pipe_diameter > 0.0 && speed > 0.0 && grain_diameter > 0.0 && gravity > 0.0,
                               "pipeline scour: pipe diameter, current speed, grain diameter and gravity must be > 0");
  mpm::verify<mpm::InputError>(11.0 * depth > roughness, "pipeline scour: water depth " + std::to_string(depth) +
                                                             " m is not above the roughness height k_s / 11 = " +
                                                             std::to_string(roughness / 11.0) + " m of the log law");
  mpm::verify<mpm::InputError>(relative_density > 1.0,
                               "pipeline scour: relative density " + std::to_string(relative_density) + " must be > 1");
  PipelineScourPrediction p;
  p.friction_velocity = speed / (2.5 * std::log(11.0 * depth / roughness));
  const double reduced = gravity * (relative_density - 1.0);
  p.shields_number = p.friction_velocity * p.friction_velocity / (reduced * grain_diameter);
  p.scour_depth = 0.6 * pipe_diameter;
  const double t_star = std::pow(p.shields_number, -5.0 / 3.0) / 50.0;
  p.time_scale = t_star * pipe_diameter * pipe_diameter / std::sqrt(reduced * std::pow(grain_diameter, 3));
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
                           const PipelineScourPrediction& prediction) {
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
