#pragma once
#include <mpm/core/scene_settings.h>
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! Chooses dt from the CFL condition on particle speed and on a wave speed, clipped to the
//! next frame boundary (state.dt_limit) and to an optional user maximum.
template <int dim>
class TimeStepControl final : public Stage<MpmState<dim>> {
public:
  struct Settings {
    double cfl = 0.5;         //!< fraction of a cell a particle may cross per step, (0, 1]
    double wave_speed = 0.0;  //!< fastest elastic wave speed of the scene [m/s] (0: none)
    double wave_cfl = 0.5;    //!< dt <= wave_cfl dx / wave_speed
    double max_dt = 1e300;    //!< user upper bound [s]
    //! Enriched particle domains stepped explicitly: dt <= wave_cfl h / wave_speed too, h the
    //! thinnest enriched domain (an implicit step has no such bound).
    bool bound_enriched = true;
  };
  explicit TimeStepControl(Settings settings) : settings_(settings) {}
  std::string name() const override { return "time_step"; }
  std::vector<std::string> reads() const override { return {"particle.v"}; }
  std::vector<std::string> writes() const override { return {"dt"}; }
  void run(MpmState<dim>& s) override;

  //! The stable step for the current particle velocities, before clipping to frame ends.
  double stable_dt(const MpmState<dim>& s) const;

private:
  Settings settings_;
};

//! max_p |v_p| [m/s] (0 for no particles), in parallel.
template <int dim>
double max_speed(const std::vector<Vec<dim>>& v);

//! The scene's time keys (cfl, wave_cfl, max_dt) with the fastest wave the scene's explicit
//! update must resolve [m/s]: every pipeline builds its time-step settings here.
template <int dim>
typename TimeStepControl<dim>::Settings time_step_settings(const SceneSettings<dim>& scene, double wave_speed) {
  typename TimeStepControl<dim>::Settings dt;
  dt.cfl = scene.cfl;
  dt.wave_cfl = scene.wave_cfl;
  dt.max_dt = scene.max_dt;
  dt.wave_speed = wave_speed;
  return dt;
}

}  // namespace mpm::stages
