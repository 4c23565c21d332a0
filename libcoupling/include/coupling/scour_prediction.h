#pragma once
//! Scour at an obstacle on a sand bed in a steady current: the published predictions a run is
//! compared with, and the exponential fit of a scour history
//! (data/reference/sumer_fredsoe2002.md).
//!
//! Undisturbed flow of depth-averaged speed U over depth h on grains of diameter d and relative
//! density s = rho_s / rho_w:
//!   friction velocity  U / U_f = 2.5 ln(11 h / k_s), k_s = 2.5 d (rough log law);
//!   Shields number     theta = U_f^2 / (g (s - 1) d);
//!   time scale         T = T* D^2 / sqrt(g (s - 1) d^3).
//! Live-bed scour (theta above the threshold of motion), history S(t) = S_eq (1 - exp(-t / T)):
//!   below a pipe of diameter D lying on the bed (Sumer & Fredsoe 2002, ch. 2; Fredsoe, Sumer &
//!   Arnskov 1992): S_eq / D = 0.6 (standard deviation 0.1), T* = theta^(-5/3) / 50;
//!   around a vertical pile of diameter D (Sumer & Fredsoe 2002, ch. 3; Breusers, Nicollet &
//!   Shen 1977; Sumer, Christiansen & Fredsoe 1992): S_eq / D = 1.3 (standard deviation 0.7),
//!   T* = (h / D) theta^(-2.2) / 2000, the current's boundary layer being the whole depth h.
#include <vector>

namespace coupling {

struct ScourPrediction {
  double friction_velocity = 0.0;  //!< U_f [m/s]
  double shields_number = 0.0;     //!< theta [-]
  double scour_depth = 0.0;        //!< S_eq [m]
  double time_scale = 0.0;         //!< T [s]
};

//! The undisturbed current of speed U over depth h on grains (d, s) under gravity g.
struct ScourCurrent {
  double speed = 0.0;             //!< U [m/s]
  double depth = 0.0;             //!< h [m]
  double grain_diameter = 0.0;    //!< d [m]
  double relative_density = 0.0;  //!< s [-]
  double gravity = 0.0;           //!< g [m/s^2]
};

//! Below a pipeline of diameter D lying on the bed. Throws mpm::InputError unless D and every
//! field of the current are positive, h > k_s / 11 and s > 1.
ScourPrediction predict_pipeline_scour(double pipe_diameter, const ScourCurrent& current);
//! Around a vertical pile of diameter D through the bed; the same errors.
ScourPrediction predict_pile_scour(double pile_diameter, const ScourCurrent& current);

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
                           const ScourPrediction& prediction);

}  // namespace coupling
