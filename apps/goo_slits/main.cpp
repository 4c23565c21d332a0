// goo_slits: a von Mises goo dropped on a plate cut with slits (paper Fig. 2). The plate is a
// level-set collider built from data/meshes/slotted_plate.obj; its slits (0.02 m) are
// narrower than a 0.05 m cell, so a coarse uniform grid sees a solid plate and the goo stays
// on top, while a grid of 0.0125 m or finer has nodes inside the slits and the goo seeps
// through. (The adaptive grid of a later stage refines only near the plate.)
//
//   goo_slits data/scenes/goo_slits.yaml                      # dx = 0.01: goo seeps through
//   goo_slits data/scenes/goo_slits.yaml --set grid.dx=0.05   # coarse: it does not
//
// diagnostics.csv adds max_penetration (deepest particle inside the plate [m]); summary.json:
// mass_fraction_through (mass below the plate at the end) and max_penetration over the run.
// --check asserts max_penetration < dx.
#include <mpm/core/app.h>
#include <mpm/core/runner.h>
#include <mpm/solid/solid_scene.h>

#include <algorithm>

using namespace mpm;

namespace {

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  solid::SolidScene<dim> solid = solid::load_solid_scene<dim>(scene);
  scene.reject_unknown_keys();
  const geometry::Collider<dim>* plate = nullptr;
  for (const auto& c : solid.colliders.colliders())
    if (c.is_level_set()) plate = &c;
  if (!plate) scene.fail("colliders", "the scene needs a level_set collider (the plate)");
  const auto& shape = std::get<geometry::LevelSetShape<dim>>(plate->shape());
  const double plate_bottom = shape.level_set().bounding_box().lo[1];

  auto pipeline = solid::make_solid_pipeline(solid);
  Runner<dim> runner("goo_slits", cl, scene, solid.settings);
  runner.set_elastic_energy([&](const MpmState<dim>& s) { return solid::elastic_energy(s, solid.materials); });
  runner.add_column("max_penetration", [&](const MpmState<dim>& s) {
    double depth = 0.0;
    for (const Vec<dim>& x : s.particles.x) depth = std::max(depth, -plate->phi(x, s.time));
    return depth;
  });
  runner.run(solid.state, pipeline);
  const std::vector<double> depths = runner.history("max_penetration");
  const double penetration = *std::max_element(depths.begin(), depths.end());

  const Particles<dim>& P = solid.state.particles;
  double through = 0.0, total = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    total += P.mass[p];
    if (P.x[p][1] < plate_bottom) through += P.mass[p];
  }
  runner.write_summary({{"mass_fraction_through", through / total}, {"max_penetration", penetration}});
  if (cl.check) return check_value("max_penetration", penetration, 0.0, solid.settings.dx) ? 0 : 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "goo_slits", "von Mises goo through sub-cell slits", run<2>, run<3>);
}
