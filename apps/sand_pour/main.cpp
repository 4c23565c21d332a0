// sand_pour: sand poured from an emitter above a tank of water falls in, settles through the
// water and builds a submerged pile. The scene is a coupled scene file
// (coupling/scene_loader.h) whose `emitters` list holds the sand stream (phase: sediment), plus
//
//   pile: {packing_fraction: 0.6}   # phi of the settled pile, for its height profile
//
//   sand_pour data/scenes/sand_pour.yaml
//
// Output as every app (mpm/core/runner.h: fluid_ and sediment_NNNN.h5, previews, checkpoints);
// diagnostics.csv adds inflow_mass_sediment (poured so far) [kg], pile_height (highest column
// of the pile, coupling/bed_profile.h) [m], pile_width (extent along x of the columns higher
// than 10 % of pile_height) [m], the kinetic energy of the grains [J] (per metre in 2D) and
// the counts of continuum and discrete grains.
// summary.json: poured_mass [kg], pile_height, pile_width [m], repose_angle (atan of
// 2 pile_height / pile_width, the slope of a triangle of the same height and base) [deg],
// sediment_mass_balance_error (|M_in - M| / M_in, round-off).
// --check: the grain mass balance below 1e-12 and a pile formed (pile_height > 0).
#include <coupling/bed_profile.h>
#include <coupling/coupled_runner.h>
#include <coupling/scene_loader.h>
#include <coupling/stages/reclassify_sediment.h>
#include <mpm/core/app.h>
#include <mpm/core/command_line.h>
#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

using namespace mpm;

namespace {

//! (height, width) of the pile: the highest column, and the x extent of the columns above
//! 10 % of it.
template <int dim>
std::pair<double, double> pile_shape(const coupling::BedProfile<dim>& bed, const Particles<dim>& grains) {
  const std::vector<double> h = bed.heights(grains);
  const double top = h.empty() ? 0.0 : *std::max_element(h.begin(), h.end());
  double lo = 1e300, hi = -1e300;
  for (std::size_t c = 0; c < h.size(); ++c)
    if (top > 0.0 && h[c] > 0.1 * top) {
      const double x = bed.centre(static_cast<std::int64_t>(c))[0];
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  return {top, top > 0.0 ? hi - lo : 0.0};
}

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  coupling::CoupledScene<dim> tank = coupling::load_coupled_scene<dim>(scene);
  verify<InputError>(tank.fluid && tank.sediment && !tank.sediment_sources.empty(),
                     scene.file() + ": sand_pour needs a `fluid`, a `sediment` and an emitter of sediment");
  const coupling::BedProfile<dim> bed(tank.settings,
                                      scene.child("pile").number("packing_fraction", Range::open(0.0, 1.0)));
  scene.reject_unknown_keys();

  auto pipeline = coupling::make_coupled_pipeline(tank);
  coupling::CoupledRunner<dim> runner("sand_pour", cl, scene, tank.settings);
  using State = coupling::CoupledState<dim>;
  runner.add_column("pile_height", [&](const State& s) { return pile_shape(bed, s.sediment.particles).first; });
  runner.add_column("pile_width", [&](const State& s) { return pile_shape(bed, s.sediment.particles).second; });
  runner.add_column("sediment_kinetic_energy", [](const State& s) {
    double e = 0.0;
    for (std::size_t p = 0; p < s.sediment.particles.size(); ++p)
      e += 0.5 * s.sediment.particles.mass[p] * s.sediment.particles.v[p].squaredNorm();
    return e;
  });
  runner.add_column("continuum", [](const State& s) { return double(coupling::count_sediment(s).continuum); });
  runner.add_column("discrete", [](const State& s) { return double(coupling::count_sediment(s).discrete); });
  runner.run(tank.state, pipeline);

  const std::vector<double> poured = runner.history("inflow_mass_sediment"), held = runner.history("mass_sediment"),
                            removed = runner.history_or_zero("outflow_mass_sediment");
  double balance = 0.0;
  for (std::size_t f = 0; f < held.size(); ++f)
    if (poured[f] > 0.0) balance = std::max(balance, std::abs(poured[f] - removed[f] - held[f]) / poured[f]);
  const auto [height, width] = pile_shape(bed, tank.state.sediment.particles);
  const double angle = width > 0.0 ? std::atan(2.0 * height / width) * 180.0 / std::numbers::pi : 0.0;
  runner.write_summary({{"poured_mass", poured.back()},
                        {"pile_height", height},
                        {"pile_width", width},
                        {"repose_angle", angle},
                        {"sediment_mass_balance_error", balance}});
  if (!cl.check) return 0;
  const bool ok = check_value("sediment_mass_balance_error", balance, 0.0, 1e-12);
  std::printf("check pile_height > 0: %.6g m %s\n", height, height > 0.0 ? "ok" : "FAILED");
  return ok && height > 0.0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "sand_pour", "Sand poured into a tank of water (coupled step, emitter)", run<2>,
                       run<3>);
}
