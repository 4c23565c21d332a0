// sediment_transport: the flagship scene. A water current over an erodible sand bed in a flume
// scours the bed around an obstacle and deposits the sand downstream. In 2D the obstacle is a
// pipeline lying on the bed (scour below pipelines); in 3D a vertical pile through the bed
// (pier scour). Water enters through the inflow face over the water section above the bed and
// leaves over the free overfall of the outflow face, with any sand carried out; sills of bed
// height at both ends hold the bed in place. The scene is a coupled scene file
// (coupling/scene_loader.h) with inflow and outflow (mpm/geometry/flow_boundary_config.h), plus
//
//   scour_window: {lo: [0.5, 0], hi: [0.8, 0]}   # [m]: the columns (x, and z in 3D; y is
//                                                # ignored) where scour and deposition count
//
//   sediment_transport data/scenes/sediment_transport.yaml
//   sediment_transport data/scenes/sediment_transport_3d.yaml
//
// Bed heights per column (coupling/bed_profile.h) with the bed's sediment.packing_fraction.
// Output as every app (mpm/core/runner.h: fluid_ and sediment_NNNN.h5, previews, checkpoints);
// diagnostics.csv adds scour_depth (largest drop of the bed below its initial height in the
// window) [m], deposition_height (largest rise) [m], the inflow and outflow masses of each phase
// [kg] (per metre of width in 2D) and the counts of continuum and discrete grains.
// bed_profile.csv: x [, z], initial and final bed height [m] of every column.
// summary.json: max_scour_depth, final_scour_depth, final_deposition_height [m],
// sediment_outflow_mass [kg], fluid_mass_balance_error and sediment_mass_balance_error
// (|M(0) + M_in - M_out - M| / (M(0) + M_in), round-off), the water's particle spacing, and with
// `pipeline: {diameter: D}` (2D) or `pile: {diameter: D}` (3D) the comparison with scour
// experiments (coupling/scour_prediction.h, data/reference/sumer_fredsoe2002.md), in the bed's
// time (the flow's since sediment.hold_until, times the bed-load closure's morphological_factor,
// coupling/bed_load.h).
// --check: both mass balances below 1e-12 and a scour hole formed (max_scour_depth > 0).
#include <coupling/bed_profile.h>
#include <coupling/coupled_runner.h>
#include <coupling/scene_loader.h>
#include <coupling/scour_prediction.h>
#include <coupling/stages/reclassify_sediment.h>
#include <mpm/core/app.h>
#include <mpm/core/command_line.h>
#include <mpm/core/error.h>
#include <mpm/geometry/particle_spacing.h>
#include <mpm/io/atomic_file.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace mpm;

namespace {

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  coupling::CoupledScene<dim> flume = coupling::load_coupled_scene<dim>(scene);
  verify<InputError>(flume.fluid && flume.sediment && flume.state.sediment.particles.size() > 0,
                     scene.file() + ": sediment_transport needs a `fluid`, a `sediment` and a sediment body");
  const Config window = scene.child("scour_window");
  const Vec<dim> window_lo = window.template vector<dim>("lo"), window_hi = window.template vector<dim>("hi");
  // The comparison with scour experiments (coupling/scour_prediction.h) below a `pipeline` or
  // around a `pile` of the scene's diameter: the undisturbed current is the inflow's (speed
  // along its face, depth = the inlet's height), the grains the drag law's.
  std::optional<coupling::ScourPrediction> predicted;
  const std::optional<Config> pipe = scene.optional_child("pipeline"), pile = scene.optional_child("pile");
  verify<InputError>(!(pipe && pile), scene.file() + ": give `pipeline` or `pile`, not both");
  if (pipe || pile) {
    const double diameter = (pipe ? *pipe : *pile).number("diameter", Range::positive());
    verify<InputError>(flume.flow.inflow.has_value(), scene.file() + ": `" + std::string(pipe ? "pipeline" : "pile") +
                                                          "` needs an `inflow` (the current)");
    const auto& in = *flume.flow.inflow;
    const coupling::ScourCurrent current{std::abs(in.velocity[in.face.axis]), in.hi[1] - in.lo[1],
                                         scene.child("drag").number("grain_diameter", Range::positive()),
                                         flume.sediment->density / flume.fluid->density, flume.settings.gravity.norm()};
    predicted =
        pipe ? coupling::predict_pipeline_scour(diameter, current) : coupling::predict_pile_scour(diameter, current);
  }
  scene.reject_unknown_keys();

  coupling::CoupledState<dim>& s = flume.state;
  const coupling::BedProfile<dim> bed(flume.settings,
                                      scene.child("sediment").number("packing_fraction", Range::open(0.0, 1.0)));
  const std::vector<double> h0 = bed.heights(s.sediment.particles);
  const double fluid0 = s.fluid.particles.total_mass(), grains0 = s.sediment.particles.total_mass();

  auto pipeline = coupling::make_coupled_pipeline(flume);
  coupling::CoupledRunner<dim> runner("sediment_transport", cl, scene, flume.settings);
  const auto change = [&](const coupling::CoupledState<dim>& st) {
    return bed.change(h0, bed.heights(st.sediment.particles), window_lo, window_hi);
  };
  runner.add_column("scour_depth", [&](const coupling::CoupledState<dim>& st) { return change(st).first; });
  runner.add_column("deposition_height", [&](const coupling::CoupledState<dim>& st) { return change(st).second; });
  runner.add_column("continuum", [](const coupling::CoupledState<dim>& st) {
    return double(coupling::count_sediment(st).continuum);
  });
  runner.add_column(
      "discrete", [](const coupling::CoupledState<dim>& st) { return double(coupling::count_sediment(st).discrete); });
  // How evenly the clear water's particles fill it (geometry/particle_spacing.h): cells that hold
  // sand do not count, since the pore water moves with the bed and through it.
  // Computed once per frame (both columns read it).
  struct {
    Index step = -1;
    geometry::ParticleSpacing value;
  } cached;
  const auto spacing = [&](const coupling::CoupledState<dim>& st) -> const geometry::ParticleSpacing& {
    if (st.step == cached.step) return cached.value;
    cached.step = st.step;
    cached.value = geometry::particle_spacing<dim>(st.fluid.particles.x, st.fluid.grid.origin(), flume.settings.dx,
                                                   st.sediment.particles.x);
    return cached.value;
  };
  runner.add_column("water_spacing_cv", [&](const coupling::CoupledState<dim>& st) { return spacing(st).count_cv; });
  runner.add_column("water_empty_share",
                    [&](const coupling::CoupledState<dim>& st) { return spacing(st).empty_share; });
  runner.run(s, pipeline);

  // The bed profile at the end, and the balances from the diagnostics.
  const std::vector<double> h = bed.heights(s.sediment.particles);
  std::ostringstream profile;
  profile.precision(9);
  profile << (dim == 3 ? "x,z,initial_height,final_height\n" : "x,initial_height,final_height\n");
  for (std::size_t c = 0; c < h.size(); ++c) {
    const Vec<dim> x = bed.centre(std::int64_t(c));
    profile << x[0] << "," << (dim == 3 ? std::to_string(x[dim - 1]) + "," : "") << h0[c] << "," << h[c] << "\n";
  }
  io::write_file_atomically(runner.out_dir() / "bed_profile.csv", profile.str());

  const auto balance = [&](const char* in, const char* out, const char* mass, double m0) {
    const std::vector<double> m_in = runner.history_or_zero(in), m_out = runner.history_or_zero(out),
                              m = runner.history(mass);
    double error = 0.0;
    for (std::size_t f = 0; f < m.size(); ++f)
      error = std::max(error, std::abs(m0 + m_in[f] - m_out[f] - m[f]) / (m0 + m_in[f]));
    return error;
  };
  const double fluid_error = balance("inflow_mass_fluid", "outflow_mass_fluid", "mass_fluid", fluid0);
  const double grain_error = balance("inflow_mass_sediment", "outflow_mass_sediment", "mass_sediment", grains0);
  const std::vector<double> scour = runner.history("scour_depth");
  const double max_scour = *std::max_element(scour.begin(), scour.end());
  const auto [final_scour, final_deposit] = change(s);
  std::vector<std::pair<std::string, double>> results = {
      {"max_scour_depth", max_scour},
      {"final_scour_depth", final_scour},
      {"final_deposition_height", final_deposit},
      {"sediment_outflow_mass", runner.history_or_zero("outflow_mass_sediment").back()},
      {"fluid_mass_balance_error", fluid_error},
      {"sediment_mass_balance_error", grain_error},
      {"water_spacing_cv", runner.history("water_spacing_cv").back()},
      {"water_empty_share", runner.history("water_empty_share").back()}};
  const std::vector<double> times = runner.history("time");
  // The bed's time: from its release (sediment.hold_until), times the bed-load closure's
  // morphological factor.
  const double morphological = flume.bed_load ? flume.bed_load->morphological_factor : 1.0;
  std::vector<double> bed_times = times;
  for (double& t : bed_times) t = std::max(0.0, t - flume.sediment->hold_until) * morphological;
  if (predicted && std::count_if(bed_times.begin(), bed_times.end(), [](double t) { return t > 0.0; }) >= 2) {
    // Against Sumer & Fredsoe (data/reference/sumer_fredsoe2002.md): the scour history fitted
    // by S_eq (1 - exp(-t / T)); a run shorter than T extrapolates S_eq.
    const coupling::ScourFit fit = coupling::fit_scour_history(bed_times, scour);
    results.insert(results.end(), {{"shields_number", predicted->shields_number},
                                   {"predicted_scour_depth", predicted->scour_depth},
                                   {"predicted_time_scale", predicted->time_scale},
                                   {"fitted_scour_depth", fit.equilibrium_depth},
                                   {"fitted_time_scale", fit.time_scale},
                                   {"fit_rms_error", fit.rms_error},
                                   {"scour_depth_ratio", fit.equilibrium_depth / predicted->scour_depth},
                                   {"time_scale_ratio", fit.time_scale / predicted->time_scale},
                                   {"scour_history_error", coupling::scour_history_error(bed_times, scour, *predicted)},
                                   {"morphological_factor", morphological}});
  }
  runner.write_summary(results);
  if (!cl.check) return 0;
  bool ok = check_value("fluid_mass_balance_error", fluid_error, 0.0, 1e-12);
  ok = check_value("sediment_mass_balance_error", grain_error, 0.0, 1e-12) && ok;
  std::printf("check max_scour_depth > 0: %.6g m %s\n", max_scour, max_scour > 0.0 ? "ok" : "FAILED");
  return ok && max_scour > 0.0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "sediment_transport",
                       "A current over an erodible sand bed with an obstacle: scour and deposition (coupled step)",
                       run<2>, run<3>);
}
