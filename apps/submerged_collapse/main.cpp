// submerged_collapse: a granular column collapses under a liquid, the experiment of Rondon,
// Pouliquen & Aussillous (2011, Phys. Fluids 23:073301; data/reference/rondon2011.md), whose
// outcome depends on the initial packing: loose columns (phi ~ 0.55) flow far and fast over a
// positive excess pore pressure, dense ones (phi ~ 0.60) creep over a negative one. The scene
// is a coupled scene file (coupling/scene_loader.h): a sediment body and a fluid body that
// fills its pores; sediment.packing_fraction sets phi.
//
//   submerged_collapse data/scenes/submerged_collapse.yaml
//   submerged_collapse data/scenes/submerged_collapse.yaml --set sediment.packing_fraction=0.60
//       --set bodies.0.hi=[0.07,0.052] --set time.end=10          (the dense run, one line)
//
// Output as every app (mpm/core/runner.h: fluid_ and sediment_NNNN.h5, previews, checkpoints);
// diagnostics.csv adds front and height of the grains [m], their kinetic energy
// sediment_kinetic_energy [J/m in 2D], the continuum / discrete counts and, with a fluid,
// base_pore_pressure [Pa]: the excess pore pressure under the column, the mean pressure of the
// second cell row above its base from 20 % to 60 % of its length (a sensor dx apart, at least
// one), less that of the cell at the same height at the far end of the liquid (the hydrostatic
// part cancels), and deposit_front [m]: the far edge of the last dx-wide column holding at least
// 2 mm of grains at the initial packing.
// summary.json:
//   deposit_runout  final minus initial deposit_front [m] (what the experiment's front means)
//   deposit_runout_error  |deposit_runout / experiment.deposit_runout - 1|, when the scene has
//                 the key `experiment.deposit_runout` [m] (> 0): the measured runout
//   runout        final front minus initial front [m]; front = the 99.5th percentile of the
//                 x of the continuum grains (the deposit; discrete grains suspended ahead of it
//                 do not count; diagnostics column front_grains counts every grain)
//   final_height  height of the deposit at the end [m]: the 99.5th percentile of the grains'
//                 y over the left half of the initial column
//   duration      first time after the peak at which the grains' kinetic energy falls below
//                 1e-3 of its peak [s] (frame resolution; time.end when it never does)
//   mean_base_pore_pressure_1s  the mean of base_pore_pressure over the frames of the first
//                 second [Pa]: positive under a contracting (loose) column, negative under a
//                 dilating (dense) one
// --check: the grains came to rest before time.end, spread (runout > 0) and the column lost
// height, and the grain mass is unchanged.
#include <coupling/bed_profile.h>
#include <coupling/coupled_runner.h>
#include <coupling/pressure_probe.h>
#include <coupling/scene_loader.h>
#include <mpm/core/app.h>
#include <mpm/core/command_line.h>
#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>
#include <vector>

using namespace mpm;

namespace {

constexpr double kDepositThickness = 2e-3;  //!< [m], deposit_front

//! The q-quantile of `values` (nearest rank); 0 when empty.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[static_cast<std::size_t>(k)];
}

//! The 99.5th percentile of the x of the grains; `deposit`: of the continuum grains only (all
//! when none is), so that grains the flow has suspended ahead do not count.
template <int dim>
double front(const coupling::CoupledState<dim>& s, bool deposit) {
  const Particles<dim>& P = s.sediment.particles;
  const bool all = !deposit || coupling::count_sediment(s).continuum == 0;
  std::vector<double> x;
  for (std::size_t p = 0; p < P.size(); ++p)
    if (all || P.material[p] != coupling::discrete_grain) x.push_back(P.x[p][0]);
  return quantile(std::move(x), 0.995);
}

//! The deposit's front [m]: the far edge of the last column (in x, from the back wall) whose
//! bed holds at least `thickness` of grains at the packing phi (coupling/bed_profile.h), so that
//! a few grains spread thin ahead of the deposit do not count.
template <int dim>
double deposit_front(const coupling::CoupledState<dim>& s, const coupling::BedProfile<dim>& bed, double thickness,
                     double dx) {
  const std::vector<double> h = bed.heights(s.sediment.particles);
  double front = 0.0;
  for (std::int64_t c = 0; c < bed.column_count(); ++c)
    if (h[static_cast<std::size_t>(c)] >= thickness) front = std::max(front, bed.centre(c)[0] + 0.5 * dx);
  return front;
}

template <int dim>
double height(const coupling::CoupledState<dim>& s, double left_of) {
  std::vector<double> y;
  for (const Vec<dim>& p : s.sediment.particles.x)
    if (p[0] < left_of) y.push_back(p[1]);
  return quantile(std::move(y), 0.995);
}

//! The lower-left corner and upper-right corner of the particles' positions.
template <int dim>
std::pair<Vec<dim>, Vec<dim>> bounds(const Particles<dim>& P) {
  Vec<dim> lo = Vec<dim>::Constant(1e300), hi = Vec<dim>::Constant(-1e300);
  for (const Vec<dim>& x : P.x) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  return {lo, hi};
}

template <int dim>
double grain_kinetic_energy(const coupling::CoupledState<dim>& s) {
  const Particles<dim>& P = s.sediment.particles;
  double e = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) e += 0.5 * P.mass[p] * P.v[p].squaredNorm();
  return e;
}

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  coupling::CoupledScene<dim> col = coupling::load_coupled_scene<dim>(scene);
  // Without `fluid` the same column collapses dry: the coupled pipeline runs the sediment's
  // stages only (issue 5, lean scenes).
  verify<InputError>(col.sediment.has_value() && col.state.sediment.particles.size() > 0,
                     scene.file() + ": submerged_collapse needs a `sediment` and a sediment body");
  // The experiment's runout, when the scene names it: the summary then gives the error.
  std::optional<double> measured_runout;
  if (const std::optional<Config> experiment = scene.optional_child("experiment"))
    measured_runout = experiment->number("deposit_runout", Range::positive());
  scene.reject_unknown_keys();
  coupling::CoupledState<dim>& s = col.state;
  const double front0 = front(s, true), left_half = 0.5 * front0, height0 = height(s, left_half);
  const double grains0 = s.sediment.particles.total_mass();

  auto pipeline = coupling::make_coupled_pipeline(col);
  coupling::CoupledRunner<dim> runner("submerged_collapse", cl, scene, col.settings);
  runner.add_column("front", [](const coupling::CoupledState<dim>& st) { return front(st, true); });
  // 2 mm: about ten grain diameters of the experiment, the thinnest deposit it draws.
  const coupling::BedProfile<dim> bed(
      col.settings, scene.optional_child("sediment")->number("packing_fraction", 0.6, Range::open(0.0, 1.0)));
  const double deposit_front0 = deposit_front(s, bed, kDepositThickness, col.settings.dx);
  runner.add_column("deposit_front", [&, dx = col.settings.dx](const coupling::CoupledState<dim>& st) {
    return deposit_front(st, bed, kDepositThickness, dx);
  });
  runner.add_column("front_grains", [](const coupling::CoupledState<dim>& st) { return front(st, false); });
  runner.add_column("height", [=](const coupling::CoupledState<dim>& st) { return height(st, left_half); });
  runner.add_column("sediment_kinetic_energy",
                    [](const coupling::CoupledState<dim>& st) { return grain_kinetic_energy(st); });
  runner.add_column("continuum", [](const coupling::CoupledState<dim>& st) {
    return double(coupling::count_sediment(st).continuum);
  });
  runner.add_column(
      "discrete", [](const coupling::CoupledState<dim>& st) { return double(coupling::count_sediment(st).discrete); });
  // The pore-pressure sensor under the column and its hydrostatic reference at the far end.
  if (const coupling::PressureProbe<dim> pressure = coupling::liquid_pressure_probe(col, pipeline)) {
    const auto [grains_lo, grains_hi] = bounds(s.sediment.particles);
    const Vec<dim> fluid_hi = bounds(s.fluid.particles).second;
    // The second cell row above the column's base (the first touches the floor's prescribed
    // nodes), from 20 % to 60 % of its length; the reference: the same row at the far end.
    const double dx = col.settings.dx;
    std::vector<Vec<dim>> sensor;
    Vec<dim> x = 0.5 * (grains_lo + grains_hi);
    x[1] = grains_lo[1] + 1.5 * dx;
    for (x[0] = grains_lo[0] + 0.2 * (grains_hi[0] - grains_lo[0]);
         x[0] <= grains_lo[0] + 0.6 * (grains_hi[0] - grains_lo[0]); x[0] += dx)
      sensor.push_back(x);
    Vec<dim> reference = x;
    reference[0] = fluid_hi[0] - dx;
    runner.add_column("base_pore_pressure", [=](const coupling::CoupledState<dim>& st) {
      double sum = 0.0;
      for (const Vec<dim>& at : sensor) sum += pressure(st, at);
      return sum / static_cast<double>(sensor.size()) - pressure(st, reference);
    });
  }
  runner.run(s, pipeline);

  const std::vector<double> time = runner.history("time"), energy = runner.history("sediment_kinetic_energy");
  const auto peak = std::max_element(energy.begin(), energy.end());
  double duration = col.settings.end_time;
  for (auto e = peak; e != energy.end(); ++e)
    if (*e < 1e-3 * *peak) {
      duration = time[static_cast<std::size_t>(e - energy.begin())];
      break;
    }
  // The frames' pore pressure is noisy (a few cells of a flowing mixture, step to step): the
  // summary gives its mean over the first second of the collapse, where the sign is decided.
  double early_pore_pressure = 0.0;
  if (s.has_fluid) {
    const std::vector<double> p = runner.history("base_pore_pressure");
    int frames = 0;
    for (std::size_t k = 0; k < p.size(); ++k)
      if (time[k] > 0.0 && time[k] <= 1.0 + 1e-9) {
        early_pore_pressure += p[k];
        ++frames;
      }
    if (frames > 0) early_pore_pressure /= frames;
  }
  const double grains = s.sediment.particles.total_mass();
  const double runout = front(s, true) - front0, final_height = height(s, left_half);
  const double deposit_runout = deposit_front(s, bed, kDepositThickness, col.settings.dx) - deposit_front0;
  std::vector<std::pair<std::string, double>> results{{"runout", runout},
                                                      {"deposit_runout", deposit_runout},
                                                      {"final_height", final_height},
                                                      {"duration", duration},
                                                      {"initial_front", front0},
                                                      {"initial_height", height0},
                                                      {"peak_sediment_kinetic_energy", energy.empty() ? 0.0 : *peak},
                                                      {"mean_base_pore_pressure_1s", early_pore_pressure}};
  if (measured_runout) results.emplace_back("deposit_runout_error", std::abs(deposit_runout / *measured_runout - 1.0));
  runner.write_summary(results);
  if (!cl.check) return 0;
  auto check = [](const char* what, bool pass, double value) {
    std::printf("check %s: %.6g %s\n", what, value, pass ? "ok" : "FAILED");
    return pass;
  };
  bool ok = check("duration < time.end [s]", duration < col.settings.end_time, duration);
  ok = check("runout > 0 [m]", runout > 0.0, runout) && ok;
  ok = check("final_height < initial_height [m]", final_height < height0, final_height) && ok;
  ok = check_value("grain mass", grains, grains0, 1e-12 * grains0) && ok;
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "submerged_collapse",
                       "Collapse of a granular column under water (coupled step, continuum/discrete grains)", run<2>,
                       run<3>);
}
