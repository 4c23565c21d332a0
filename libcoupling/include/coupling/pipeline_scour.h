#pragma once
//! Scour below a pipeline on a sand bed in a steady current: the published predictions a run is
//! compared with, and the exponential fit of a scour history (data/reference/sumer_fredsoe2002.md).
//!
//! Undisturbed flow of depth-averaged speed U over depth h on grains of diameter d and relative
//! density s = rho_s / rho_w:
//!   friction velocity  U / U_f = 2.5 ln(11 h / k_s), k_s = 2.5 d (rough log law);
//!   Shields number     theta = U_f^2 / (g (s - 1) d).
//! Live-bed scour (theta above the threshold of motion) below a pipe of diameter D lying on the
//! bed (Sumer & Fredsoe 2002, ch. 2; Fredsoe, Sumer & Arnskov 1992):
//!   equilibrium depth  S / D = 0.6 (standard deviation 0.1 over the experiments);
//!   time scale         T* = sqrt(g (s - 1) d^3) T / D^2 = theta^(-5/3) / 50;
//!   history            S(t) = S_eq (1 - exp(-t / T)).
#include <vector>

namespace coupling {

struct PipelineScourPrediction {
  double friction_velocity = 0.0;  //!< U_f [m/s]
  double shields_number = 0.0;     //!< theta [-]
  double scour_depth = 0.0;        //!< S_eq [m]
  double time_scale = 0.0;         //!< T [s]
};

//! Throws mpm::InputError unless every argument is positive, h > k_s / 11 and s > 1.
PipelineScourPrediction predict_pipeline_scour(double pipe_diameter, double speed, double depth, double grain_diameter,
                                               double relative_density, double gravity);

struct ScourFit {
  double equilibrium_depth = 0.0;  //!< S_eq [m]
  double time_scale = 0.0;         //!< T [s]
  double rms_error = 0.0;          //!< root mean square of S(t_i) - S_i [m]
};

//! Least-squares fit of S(t) = S_eq (1 - exp(-t / T)) to the samples (t_i, S_i): for each T of a
//! logarithmic grid from 1e-3 to 1e3 times the last time (then refined by golden section
//! around the best) S_eq is linear and solved exactly. At least two samples with t > 0.
ScourFit fit_scour_history(const std::vector<double>& time, const std::vector<double>& depth);

//! The root mean square over the samples with t > 0 of S_i - S_eq (1 - exp(-t_i / T)), the
//! predicted history, over S_eq: how far a run's scour history lies from the experiments' (0:
//! on it; 1: off by the equilibrium depth throughout). Needs a sample with t > 0.
double scour_history_error(const std::vector<double>& time, const std::vector<double>& depth,
                           const PipelineScourPrediction& prediction);

}  // namespace coupling
