#pragma once
//! The step loop of every run (the Runner's frames, coupled tests, user codes): steps a
//! pipeline until the state's clock reaches a target time. The time-step stage clips dt to
//! state.dt_limit, the time left, so the step that takes all of it ends exactly on t_end.
#include <mpm/core/error.h>
#include <mpm/core/pipeline.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

namespace mpm {

//! One step towards t_end: the time-step stage sees the time left as state.dt_limit, and the
//! clock lands exactly on t_end when the step takes all of it. For loops that look at the state
//! after every step; advance() is the loop itself.
template <class State>
void step_towards(State& state, Pipeline<State>& pipeline, double t_end) {
  state.dt_limit = t_end - state.time;
  pipeline.step(state);
  state.time = state.dt >= state.dt_limit ? t_end : state.time + state.dt;
  ++state.step;
}

//! Steps `pipeline` until state.time is within `slack` [s] of t_end, and never closer than the
//! clock's round-off: 16 ulps of t_end, or 1e-9 of the last step. A clock that adds hundreds of
//! steps drifts by that much from targets built another way (200 steps of 2.5e-4 s from
//! t = 0.25 end 5.5e-15 s short of 0.3), and the sliver step that would close such a gap is
//! below what a step can resolve (a pressure solve scaled by dt loses all precision). Returns
//! true. With `stop`,
//! asks it after every step and returns false, leaving the state after that step, when it says
//! so (a graceful stop, core/stop_signals.h). NumericalError, naming the time-step stage, when a
//! step is not positive or more than `max_steps` steps do not get there (a collapsing step ends
//! the run instead of hanging it). State has time, dt, dt_limit and step (MpmState,
//! libcoupling's CoupledState).
template <class State>
bool advance(State& state, Pipeline<State>& pipeline, double t_end, std::int64_t max_steps = 1000000,
             double slack = 0.0, bool (*stop)() = nullptr) {
  std::int64_t steps = 0;
  slack = std::max(slack, 16.0 * std::numeric_limits<double>::epsilon() * std::abs(t_end));
  while (state.time < t_end - std::max(slack, 1e-9 * state.dt)) {
    step_towards(state, pipeline, t_end);
    if (!(state.dt > 0.0) || ++steps > max_steps) {
      char why[256];
      std::snprintf(why, sizeof why,
                    "stage 'time_step': the time step collapsed to %.6g s at t = %.6g s (more than %lld steps "
                    "to reach t = %.6g s)",
                    state.dt, state.time, static_cast<long long>(max_steps), t_end);
      throw NumericalError(why);
    }
    if (stop && stop() && state.time < t_end - std::max(slack, 1e-9 * state.dt)) return false;
  }
  return true;
}

}  // namespace mpm
