// lid_driven_cavity: a 2D square cavity of side L full of liquid, the lid (y = L) sliding at
// speed U, the other walls at rest (no-slip); Re = U L / nu. Runs towards the steady vortex.
//
//   lid_driven_cavity data/scenes/lid_driven_cavity.yaml
//   lid_driven_cavity data/scenes/lid_driven_cavity.yaml --set cavity.reynolds=400 --set time.end=30
//
// Writes centerline_u.csv (y, u along x = L/2) and centerline_v.csv (x, v along y = L/2) from
// the node velocities at the end, in units of L and U. summary.json: the extremes u_min,
// v_min, v_max of those lines and, for Re = 100, Ghia, Ghia & Shin 1982 (J. Comput. Phys. 48,
// 387-411, Tables I and II: u_min = -0.21090, v_max = 0.17527, v_min = -0.24533), and the
// relative change of the kinetic energy over the last 10 % of the run (steadiness).
// --check (Re = 100 only): the three extremes within 15 % of Ghia et al.
#include <fluid/scene/fluid_scene.h>

#include <mpm/core/app.h>
#include <mpm/core/error.h>
#include <mpm/core/runner.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

using namespace mpm;

namespace {

//! Writes "position,velocity" along the node line through the cavity centre: component
//! `along` of position, component `comp` of velocity; returns (min, max) of the velocity / U.
std::pair<double, double> write_centerline(const std::filesystem::path& file, const SparseGrid<2>& g, int along,
                                           int comp, double L, double U, const std::string& header) {
  std::ofstream out(file);
  if (!out) throw IoError("cannot write " + file.string());
  out << header << "\n";
  const int n = static_cast<int>(std::lround(L / g.dx()));
  IVec<2> node;
  node[1 - along] = static_cast<int>(std::lround((0.5 * L - g.origin()[1 - along]) / g.dx()));
  double lo = 0.0, hi = 0.0;
  for (int i = 0; i <= n; ++i) {
    node[along] = static_cast<int>(std::lround(-g.origin()[along] / g.dx())) + i;
    const Index k = g.node_index(node);
    const double v = k >= 0 ? g.velocity[k][comp] / U : 0.0;
    out << (i * g.dx()) / L << "," << v << "\n";
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return {lo, hi};
}

int run2(const CommandLine& cl, const Config& scene) {
  // 1. The cavity [0, L]^2, walls outside it, and the lid.
  const Config cavity = scene.child("cavity");
  const double L = cavity.number("size", 1.0, Range::positive());
  const double U = cavity.number("lid_speed", 1.0, Range::positive());
  const double Re = cavity.number("reynolds", 100.0, Range::positive());
  const int cells = cavity.integer("cells", 32, 4, 4096);
  const int ppc = geometry::particles_per_cell<2>(cavity);
  const double dx = L / cells;
  const double layer = wall_layer(parse_kernel(scene), dx);
  const DerivedDomain<2> domain{Vec<2>::Constant(-layer), Vec<2>::Constant(L + layer), dx};
  SceneSettings<2> settings = parse_scene_settings<2>(scene, domain);
  fluid::FluidMaterial liquid;
  liquid.density = scene.child("fluid").number("density", 1000.0, Range::positive());
  liquid.viscosity = liquid.density * U * L / Re;
  auto colliders = geometry::parse_colliders<2>(scene, domain.lo, domain.hi, layer);
  // The lid: a sticky half-space y >= L moving along x (it stays in place: it slides along itself).
  colliders.add(geometry::Collider<2>(geometry::HalfSpace<2>(Vec<2>(0.0, L), Vec<2>(0.0, -1.0)),
                                      geometry::Contact{geometry::ContactType::sticky, 0.0}, Vec<2>(U, 0.0)));
  if (colliders.walls() && colliders.walls()->wall(1, geometry::Side::upper))
    scene.fail("walls", "the top of the cavity is the lid: set walls.y_max: open");
  fluid::FluidScene<2> fluid =
      fluid::make_fluid_scene(settings, liquid, fluid::parse_pressure_settings(scene), colliders);
  fluid::add_fluid_particles<2>(fluid, geometry::seed_box<2>(Vec<2>::Zero(), Vec<2>::Constant(L), dx, ppc, 0.0, 1),
                                geometry::particle_volume<2>(dx, ppc), Vec<2>::Zero(), "cavity");
  scene.reject_unknown_keys();

  // 2. Run.
  auto pipeline = fluid::make_fluid_pipeline(fluid);
  Runner<2> runner("lid_driven_cavity", cl, scene, settings);
  fluid::add_pressure_columns(runner, pipeline);
  runner.run(fluid.state, pipeline);

  // 3. Centre lines, extremes, steadiness.
  const auto [u_min, u_max] = write_centerline(runner.out_dir() / "centerline_u.csv", fluid.state.grid, 1, 0, L, U, "y,u");
  const auto [v_min, v_max] = write_centerline(runner.out_dir() / "centerline_v.csv", fluid.state.grid, 0, 1, L, U, "x,v");
  const std::vector<double> kinetic = runner.history("kinetic_energy");
  const std::size_t last = kinetic.size() - 1, before = last - std::max<std::size_t>(1, last / 10);
  const double steadiness = kinetic[last] > 0.0 ? std::abs(kinetic[last] - kinetic[before]) / kinetic[last] : 0.0;
  const double ghia_u_min = -0.21090, ghia_v_max = 0.17527, ghia_v_min = -0.24533;
  std::vector<std::pair<std::string, double>> results = {
      {"reynolds", Re}, {"u_min", u_min}, {"u_max", u_max}, {"v_min", v_min}, {"v_max", v_max},
      {"kinetic_energy_change_last_10_percent", steadiness}};
  if (Re == 100.0) {
    results.emplace_back("ghia1982_u_min", ghia_u_min);
    results.emplace_back("ghia1982_v_max", ghia_v_max);
    results.emplace_back("ghia1982_v_min", ghia_v_min);
  }
  runner.write_summary(results);
  if (cl.check) {
    if (Re != 100.0) {
      std::fprintf(stderr, "check: reference values exist for reynolds = 100 only\n");
      return 1;
    }
    const bool a = check_value("u_min", u_min, ghia_u_min, 0.15 * std::abs(ghia_u_min));
    const bool b = check_value("v_max", v_max, ghia_v_max, 0.15 * ghia_v_max);
    const bool c = check_value("v_min", v_min, ghia_v_min, 0.15 * std::abs(ghia_v_min));
    return a && b && c ? 0 : 1;
  }
  return 0;
}

int run3(const CommandLine&, const Config& scene) {
  scene.fail("dim", "lid_driven_cavity is a 2D scene (dim: 2)");
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "lid_driven_cavity", "Lid-driven cavity (LANS fluid)", run2, run3);
}
