// dam_break: a water column of width a and height 2a released at the closed end of a tank
// (Martin & Moyce 1952, n^2 = 2), in 2D or in a 3D channel of depth `column.depth`.
//
//   dam_break data/scenes/dam_break.yaml
//   dam_break data/scenes/dam_break_3d.yaml
//
// diagnostics.csv adds front_position (distance from the back wall of the farthest particle
// within one cell of the floor) [m] and column_height (water depth over the first quarter
// width from the back wall, from particle volume) [m] at every output time. summary.json: the final front, the front and
// Martin & Moyce's at T = 2.5, and the largest relative deviation from their curve over
// 1 <= T <= 3, with Z = front / a and T = t sqrt(2 g / a).
// --check: Z(T = 2.5) within 20 % of the measurement (the spread between published
// simulations of this experiment, which start from an instantaneous release).
#include <fluid/scene/fluid_scene.h>

#include <mpm/core/app.h>
#include <mpm/core/runner.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <utility>

using namespace mpm;

namespace {

// Martin & Moyce 1952 (Phil. Trans. R. Soc. A 244, 312-324), Fig. 3, n^2 = 2, a = 2.25 in:
// surge front Z = x / a against T = t sqrt(2 g / a), as digitised in PySPH
// (pysph/examples/db_exp_data.py).
constexpr std::array<std::pair<double, double>, 7> martin_moyce = {
    {{0.0, 1.0}, {0.832, 1.217}, {1.219, 1.474}, {1.997, 2.292}, {2.547, 2.995}, {3.345, 4.134}, {4.034, 4.944}}};

double martin_moyce_front(double T) {
  for (std::size_t i = 1; i < martin_moyce.size(); ++i)
    if (T <= martin_moyce[i].first) {
      const auto [t0, z0] = martin_moyce[i - 1];
      const auto [t1, z1] = martin_moyce[i];
      return z0 + (z1 - z0) * (T - t0) / (t1 - t0);
    }
  return martin_moyce.back().second;
}

//! Farthest particle within one cell of the floor y = 0 [m].
template <int dim>
double front_position(const MpmState<dim>& s) {
  double front = 0.0;
  for (const Vec<dim>& x : s.particles.x)
    if (x[1] < s.grid.dx()) front = std::max(front, x[0]);
  return front;
}

//! Water depth at the back wall [m]: the particle volume in the slab 0 <= x < w, w = a / 4,
//! per unit slab area (w, or w times the channel depth in 3D). A volume average, because the
//! no-slip wall holds a film of particles on itself (fluid_scene.h) that a "highest particle"
//! measure would report as the column.
template <int dim>
double column_height(const MpmState<dim>& s, double w, double depth) {
  double volume = 0.0;
  for (std::size_t p = 0; p < s.particles.size(); ++p)
    if (s.particles.x[p][0] < w) volume += s.particles.volume0[p];
  return volume / (dim == 3 ? w * depth : w);
}

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  // 1. The column in [0, a] x [0, 2a] (x [0, depth]) and the tank around it.
  const Config column = scene.child("column");
  const double a = column.number("width", Range::positive());
  const double H = column.number("height_ratio", 2.0, Range::positive()) * a;
  const int cells = column.integer("cells_per_width", 20, 2, 4096);
  const double dx = a / cells;
  const int ppc = geometry::particles_per_cell<dim>(column);
  const double length = column.number("tank_length", 5.0 * a, Range{a, 1e308, true, false});
  // Tall enough for the run-up on the far wall (about 2 H); nothing may leave the grid.
  const double height = column.number("tank_height", 3.0 * H, Range{H, 1e308, true, false});
  const double depth = dim == 3 ? column.number("depth", a, Range::positive()) : 0.0;
  const double layer = wall_layer(parse_kernel(scene), dx);
  DerivedDomain<dim> domain{Vec<dim>::Constant(-layer), Vec<dim>::Zero(), dx};
  domain.hi[0] = length + layer;
  domain.hi[1] = height + layer;
  if constexpr (dim == 3) domain.hi[2] = depth + layer;

  // 2. Settings, water, walls, particles.
  SceneSettings<dim> settings = parse_scene_settings<dim>(scene, domain);
  auto colliders = geometry::parse_colliders<dim>(scene, domain.lo, domain.hi, layer);
  const Config liquid = scene.child("fluid");
  fluid::FluidScene<dim> water =
      fluid::make_fluid_scene(settings, fluid::parse_fluid_material(liquid), fluid::parse_pressure_settings(scene),
                              colliders, fluid::parse_fluid_solver(liquid));
  Vec<dim> hi = Vec<dim>::Zero();
  hi[0] = a;
  hi[1] = H;
  if constexpr (dim == 3) hi[2] = depth;
  fluid::add_fluid_particles<dim>(water, geometry::seed_box<dim>(Vec<dim>::Zero(), hi, dx, ppc, 0.0, 1),
                                  geometry::particle_volume<dim>(dx, ppc), Vec<dim>::Zero(), "column");
  water.solver->start_at_rest(water.state.particles, settings);
  scene.reject_unknown_keys();

  // 3. Run.
  auto pipeline = fluid::make_fluid_pipeline(water);
  Runner<dim> runner("dam_break", cl, scene, settings);
  runner.add_column("front_position", front_position<dim>);
  runner.add_column("column_height", [&](const MpmState<dim>& s) { return column_height(s, a / 4, depth); });
  runner.run(water.state, pipeline);

  // 4. The front against Martin & Moyce in dimensionless form, from every frame.
  const double g = settings.gravity.norm();
  const double T_scale = std::sqrt(2.0 * g / a);
  const std::vector<double> time = runner.history("time"), front = runner.history("front_position");
  double deviation = 0.0, Z_check = 0.0, T_check = 0.0;
  for (std::size_t f = 0; f < time.size(); ++f) {
    const double T = time[f] * T_scale, Z = front[f] / a;
    if (T >= 1.0 && T <= 3.0) deviation = std::max(deviation, std::abs(Z / martin_moyce_front(T) - 1.0));
    if (std::abs(T - 2.5) < std::abs(T_check - 2.5)) {
      T_check = T;
      Z_check = Z;
    }
  }
  const double Z_reference = martin_moyce_front(T_check);
  runner.write_summary({{"final_front_position", front_position(water.state)},
                        {"final_column_height", column_height(water.state, a / 4, depth)},
                        {"T_check", T_check},
                        {"front_Z_at_T_check", Z_check},
                        {"martin_moyce_Z_at_T_check", Z_reference},
                        {"max_relative_deviation_T_1_to_3", deviation}});
  if (cl.check) {
    if (std::abs(T_check - 2.5) > 0.25) {
      std::fprintf(stderr, "check: no output frame near T = 2.5 (closest T = %g); run longer\n", T_check);
      return 1;
    }
    return check_value("front_Z_at_T_2.5", Z_check, Z_reference, 0.2 * Z_reference) ? 0 : 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "dam_break", "Dam break (Martin & Moyce 1952), LANS fluid", run<2>, run<3>);
}
