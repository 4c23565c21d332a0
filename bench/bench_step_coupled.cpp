// bench_step's fluid and coupled cases (3D, domain [0, 1]^3 with sticky walls, dx = 1 / cells,
// 8 particles per cell), run through the coupled pipeline (coupling::make_coupled_pipeline, as
// the coupled_scene app):
//   fluid:   a water column 0.4 x 0.5 x 0.4 m released from rest on the floor (a dam break to
//            every side): P2G, the pressure projection (MGPCG, tolerance 1e-8), G2P;
//   coupled: a column 0.2 x 0.25 x 0.2 m of Drucker-Prager sand (phi = 0.6, Di Felice drag)
//            inside a water block 0.6 x 0.3 x 0.6 m, both released from rest: both phases'
//            transfers, the volume fractions, the implicit drag exchange, the mixture
//            projection, the return map.
// The reference is the same step with the textbook pressure solve: conjugate gradients without
// a preconditioner (`pressure.solver: cg`), one thread. The projection is most of a fluid step
// (docs/performance.md); the other stages are the transfers the solid cases' reference checks.
// Before timing, the totals of each phase (momentum, m x, kinetic energy) after --steps steps
// of the library and of the reference must agree to 1e-6 relative (both solves stop at a
// relative residual of 1e-8; measured differences are in docs/performance.md), else exit 1.
#include "step_timing.h"

#include <coupling/coupled_scene.h>
#include <coupling/scene_loader.h>
#include <mpm/core/config.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace bench {
namespace {

std::string box(const std::string& phase, double lo_x, double lo_y, double lo_z, double hi_x, double hi_y,
                double hi_z) {
  return "  - {phase: " + phase + ", shape: box, lo: [" + yaml_number(lo_x) + ", " + yaml_number(lo_y) + ", " +
         yaml_number(lo_z) + "], hi: [" + yaml_number(hi_x) + ", " + yaml_number(hi_y) + ", " + yaml_number(hi_z) +
         "]}\n";
}

// The scene file of a case; `solver`: the pressure solver, with its own keys after the name.
std::string scene_yaml(const std::string& name, int cells, const std::string& solver) {
  const double dx = 1.0 / cells, floor = 2 * dx;  // the inner face of the floor's wall layer
  std::string y = "dim: 3\ndomain: {lo: [0, 0, 0], hi: [1, 1, 1]}\ngrid: {dx: " + yaml_number(dx) +
                  "}\nwalls: {contact: sticky}\ntime: {end: 1, frame_dt: 1, cfl: 0.4}\ngravity: [0, -9.81, 0]\n"
                  "fluid: {density: 1000, viscosity: 1.0e-3}\n"
                  "pressure: {solver: " +
                  solver + ", tolerance: 1.0e-8, max_iterations: 100000}\n";
  if (name == "fluid") return y + "bodies:\n" + box("fluid", 0.3, floor, 0.3, 0.7, floor + 0.5, 0.7);
  y += "drag: {law: di_felice, grain_diameter: 5.0e-4}\n"
       "sediment: {density: 2650, youngs_modulus: 5.0e4, poisson_ratio: 0.3, elasticity: hencky_stvk,"
       " plasticity: {model: drucker_prager, friction_angle: 32}, packing_fraction: 0.6}\n"
       "bodies:\n";
  return y + box("sediment", 0.4, floor, 0.4, 0.6, floor + 0.25, 0.6) +
         box("fluid", 0.2, floor, 0.2, 0.8, floor + 0.3, 0.8);
}

struct Run {
  StepRun timed;
  std::vector<double> totals;  // per phase: momentum (3), m x (3), kinetic energy
  std::size_t particles = 0;
  double dt_min = 1e300, dt_max = 0;
};

void add_totals(const mpm::Particles<3>& P, std::vector<double>& t) {
  std::vector<double> s(7, 0.0);
  for (std::size_t p = 0; p < P.size(); ++p) {
    for (int a = 0; a < 3; ++a) s[a] += P.mass[p] * P.v[p][a];
    for (int a = 0; a < 3; ++a) s[3 + a] += P.mass[p] * P.x[p][a];
    s[6] += 0.5 * P.mass[p] * P.v[p].squaredNorm();
  }
  t.insert(t.end(), s.begin(), s.end());
}

Run run(const std::string& yaml, int steps) {
  coupling::CoupledScene<3> cs = coupling::load_coupled_scene<3>(mpm::Config::parse(yaml, "bench_step"));
  auto pipeline = coupling::make_coupled_pipeline(cs);
  Run r;
  r.particles = cs.state.fluid.particles.size() + cs.state.sediment.particles.size();
  const auto t0 = Clock::now();
  for (int s = 0; s < steps; ++s) {
    pipeline.step(cs.state);
    r.dt_min = std::min(r.dt_min, cs.state.dt);
    r.dt_max = std::max(r.dt_max, cs.state.dt);
  }
  r.timed = {seconds_since(t0), pipeline.times()};
  if (cs.state.has_fluid) add_totals(cs.state.fluid.particles, r.totals);
  if (cs.state.has_sediment) add_totals(cs.state.sediment.particles, r.totals);
  return r;
}

}  // namespace

bool run_coupled_case(const std::string& name, int cells, int steps, int repeat, const std::vector<int>& threads,
                      int setup_reuse) {
  const std::string library = scene_yaml(name, cells, "mgpcg, setup_reuse: " + std::to_string(setup_reuse));
  const std::string reference = scene_yaml(name, cells, "cg");
  Run check;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads.back());
    check = run(library, steps);
  }
  Run ref;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    ref = run(reference, steps);
  }
  std::vector<std::pair<int, int>> groups;  // per phase: momentum, m x, kinetic energy
  for (int phase = 0; phase + 7 <= static_cast<int>(check.totals.size()); phase += 7)
    groups.insert(groups.end(), {{phase, phase + 3}, {phase + 3, phase + 6}, {phase + 6, phase + 7}});
  const double d = max_group_difference(check.totals, ref.totals, groups), tolerance = 1e-6;
  std::printf(
      "\n%s: %zu particles, dx = 1/%d, %d steps (dt %.3g .. %.3g s); library (MGPCG) vs reference (CG) totals: max "
      "relative difference %.1e (tolerance %.0e) %s\n",
      name.c_str(), check.particles, cells, steps, check.dt_min, check.dt_max, d, tolerance,
      d < tolerance ? "ok" : "FAILED");
  if (!(d < tolerance)) return false;
  time_and_report(
      threads, repeat, static_cast<double>(check.particles) * steps,
      [&] {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        return run(reference, steps).timed.seconds;
      },
      [&] { return run(library, steps).timed; });
  return true;
}

}  // namespace bench
