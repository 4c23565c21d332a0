// coupled_scene: runs any coupled scene file (coupling/scene_loader.h) with the coupled
// pipeline, one phase or both, as solid_scene runs any solid scene file.
//
//   coupled_scene data/scenes/sediment_transport.yaml --set time.end=0.2
//
// diagnostics.csv adds pressure_iterations, pressure_residual and pressure_round_off when the scene has a fluid,
// and the inflow and outflow masses of each phase.
// summary.json: mass_fluid and mass_sediment at the end [kg] (per metre in 2D).
#include <coupling/coupled_runner.h>
#include <coupling/scene_loader.h>
#include <mpm/core/app.h>
#include <mpm/core/command_line.h>

using namespace mpm;

namespace {

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  coupling::CoupledScene<dim> cs = coupling::load_coupled_scene<dim>(scene);
  scene.reject_unknown_keys();
  auto pipeline = coupling::make_coupled_pipeline(cs);
  coupling::CoupledRunner<dim> runner("coupled_scene", cl, scene, cs.settings);
  runner.run(cs.state, pipeline);
  runner.write_summary({{"mass_fluid", cs.state.fluid.particles.total_mass()},
                        {"mass_sediment", cs.state.sediment.particles.total_mass()}});
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "coupled_scene", "Any coupled scene file (one phase or both)", run<2>, run<3>);
}
