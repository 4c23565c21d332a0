// vibrating_bar: the 1D elastic bar, fixed at x = 0 and free at x = L, started in its first
// mode v(x, 0) = v0 sin(beta x), beta = pi / (2L). Linear elasticity (nu = 0, slip walls above
// and below so the bar stays one-dimensional) gives v(x, t) = v0 sin(beta x) cos(omega t),
// omega = beta sqrt(E / rho), hence the centre-of-mass velocity
//   v_com(t) = (1/L) int_0^L v dx = (2 v0 / pi) cos(omega t).
//
//   vibrating_bar data/scenes/vibrating_bar.yaml
//   vibrating_bar data/scenes/vibrating_bar.yaml --set bar.cells=64 --set grid.kernel=cubic
//   vibrating_bar data/scenes/vibrating_bar.yaml --set adaptive.levels=2
//       --set 'adaptive.refine=[{box: {lo: [0, 0], hi: [0.5, 0.01]}}]'   (fine for x < L/2)
//
// diagnostics.csv adds com_velocity and com_velocity_exact; summary.json adds error, the
// largest |v_com - v_com_exact| / v0 over the frames, and period (2 pi / omega).
// --check asserts error < bar.check_tolerance.
#include <mpm/core/app.h>
#include <mpm/core/runner.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>
#include <mpm/solid/solid_scene.h>

#include <algorithm>
#include <cmath>
#include <numbers>

using namespace mpm;

namespace {

template <int dim>
double com_velocity(const Particles<dim>& P) {
  double momentum = 0.0, mass = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    momentum += P.mass[p] * P.v[p][0];
    mass += P.mass[p];
  }
  return momentum / mass;
}

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  // 1. The bar along x from the fixed wall at x = 0; it is `thickness_cells` cells thick.
  const Config bar = scene.child("bar");
  const double L = bar.number("length", Range::positive());
  const double v0 = bar.number("amplitude", Range::positive());
  const int cells = bar.integer("cells", 32, 2, 1 << 16);
  const double dx = L / cells;
  const double thickness = dx * bar.integer("thickness_cells", 2, 1, 64);
  const double tolerance = bar.number("check_tolerance", 0.1, Range::positive());
  // The fixed wall at x = 0; on an adaptive grid it acts on coarse nodes (dx 2^(levels-1)).
  const double layer = wall_layer(parse_kernel(scene), dx * (1 << (adaptive::levels_of(scene) - 1)));
  DerivedDomain<dim> domain{Vec<dim>::Constant(-layer), Vec<dim>::Constant(thickness + layer), dx};
  domain.hi[0] = 1.25 * L + 2 * layer;

  // 2. Settings, material, walls: the x_min wall holds the bar (sticky), the others slip.
  SceneSettings<dim> settings = parse_scene_settings<dim>(scene, domain);
  std::vector<Material<dim>> materials = {parse_material<dim>(scene.child("material"))};
  if (materials[0].lame.lambda != 0.0)
    scene.child("material").fail("poisson_ratio", "the 1D bar solution needs poisson_ratio: 0");
  auto colliders = geometry::parse_colliders<dim>(scene, domain.lo, domain.hi, layer);
  solid::SolidScene<dim> solid = solid::make_solid_scene(settings, materials, colliders);
  solid::read_adaptive_key(solid, scene);  // optional: an adaptive grid (bar.cells: the finest)
  const int ppc = geometry::particles_per_cell<dim>(bar);
  Vec<dim> hi = Vec<dim>::Constant(thickness);
  hi[0] = L;
  solid::add_particles<dim>(solid, geometry::seed_box<dim>(Vec<dim>::Zero(), hi, dx, ppc, 0.0, 1),
                            geometry::particle_volume<dim>(dx, ppc), 0, Vec<dim>::Zero(), "bar");
  const double beta = std::numbers::pi / (2 * L);
  for (std::size_t p = 0; p < solid.state.particles.size(); ++p)
    solid.state.particles.v[p][0] = v0 * std::sin(beta * solid.state.particles.x[p][0]);
  scene.reject_unknown_keys();

  // 3. Run with the centre-of-mass velocity and its exact value in the diagnostics.
  const double omega = beta * std::sqrt(materials[0].lame.p_wave_modulus() / materials[0].density);
  auto exact = [&](double t) { return 2.0 * v0 / std::numbers::pi * std::cos(omega * t); };
  auto pipeline = solid::make_solid_pipeline(solid);
  Runner<dim> runner("vibrating_bar", cl, scene, settings);
  runner.set_elastic_energy([&](const MpmState<dim>& s) { return solid::elastic_energy(s, solid.materials); });
  runner.add_column("com_velocity", [](const MpmState<dim>& s) { return com_velocity(s.particles); });
  runner.add_column("com_velocity_exact", [&](const MpmState<dim>& s) { return exact(s.time); });
  runner.run(solid.state, pipeline);

  const std::vector<double> v_com = runner.history("com_velocity"), v_exact = runner.history("com_velocity_exact");
  double error = 0.0;
  for (std::size_t f = 0; f < v_com.size(); ++f) error = std::max(error, std::fabs(v_com[f] - v_exact[f]) / v0);

  runner.write_summary({{"error", error}, {"period", 2 * std::numbers::pi / omega}, {"dx", dx}});
  if (cl.check) return check_value("error", error, 0.0, tolerance) ? 0 : 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "vibrating_bar", "1D elastic bar, first mode", run<2>, run<3>);
}
