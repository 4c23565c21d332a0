// lid_driven_cavity: a 2D square cavity of side L full of liquid, the lid (y = L) sliding at
// speed U, the other walls at rest (no-slip); Re = U L / nu. Runs towards the steady vortex.
//
//   lid_driven_cavity data/scenes/lid_driven_cavity.yaml
//   lid_driven_cavity data/scenes/lid_driven_cavity.yaml --set cavity.reynolds=1000 --set time.end=40
//
// Writes centerline_u.csv (y, u along x = L/2) and centerline_v.csv (x, v along y = L/2) from
// the node velocities at the end, in units of L and U. summary.json: the extremes u_min,
// v_min, v_max of those lines, the relative change of the kinetic energy over the last 10 % of
// the run (steadiness) and, for Re = 100 and 1000, the comparison with Ghia, Ghia & Shin 1982
// (data/reference/ghia1982.md): their extremes and the RMS error of u and v (lines linearly
// interpolated) at the 17 points of their Tables I and II, in units of U.
// --check (Re = 100 or 1000): the three extremes within 15 % of Ghia et al.
#include <fluid/scene/fluid_scene.h>

#include <mpm/core/app.h>
#include <mpm/core/error.h>
#include <mpm/core/runner.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>

using namespace mpm;

namespace {

// Ghia, Ghia & Shin 1982 (J. Comput. Phys. 48, 387-411), Table I: u / U at y / L along the
// vertical centre line; Table II: v / U at x / L along the horizontal one (129^2 grid).
constexpr std::array<double, 17> ghia_y = {1.0,    0.9766, 0.9688, 0.9609, 0.9531, 0.8516, 0.7344, 0.6172, 0.5,
                                           0.4531, 0.2813, 0.1719, 0.1016, 0.0703, 0.0625, 0.0547, 0.0};
constexpr std::array<double, 17> ghia_x = {1.0,    0.9688, 0.9609, 0.9531, 0.9453, 0.9063, 0.8594, 0.8047, 0.5,
                                           0.2344, 0.2266, 0.1563, 0.0938, 0.0781, 0.0703, 0.0625, 0.0};
struct GhiaColumns {
  double reynolds;
  std::array<double, 17> u, v;
};
constexpr std::array<GhiaColumns, 2> ghia = {{
    {100.0,
     {1.0, 0.84123, 0.78871, 0.73722, 0.68717, 0.23151, 0.00332, -0.13641, -0.20581, -0.21090, -0.15662, -0.10150,
      -0.06434, -0.04775, -0.04192, -0.03717, 0.0},
     {0.0, -0.05906, -0.07391, -0.08864, -0.10313, -0.16914, -0.22445, -0.24533, 0.05454, 0.17527, 0.17507, 0.16077,
      0.12317, 0.10890, 0.10091, 0.09233, 0.0}},
    {1000.0,
     {1.0, 0.65928, 0.57492, 0.51117, 0.46604, 0.33304, 0.18719, 0.05702, -0.06080, -0.10648, -0.27805, -0.38289,
      -0.29730, -0.22220, -0.20196, -0.18109, 0.0},
     {0.0, -0.21388, -0.27669, -0.33714, -0.39188, -0.51550, -0.42665, -0.31966, 0.02526, 0.32235, 0.33075, 0.37095,
      0.32627, 0.30353, 0.29012, 0.27485, 0.0}},
}};

//! Writes "position,velocity" along the node line through the cavity centre: component
//! `along` of position, component `comp` of velocity; returns the velocities / U at the n + 1
//! nodes s = i dx / L, i = 0..n.
std::vector<double> write_centerline(const std::filesystem::path& file, const SparseGrid<2>& g, int along, int comp,
                                     double L, double U, const std::string& header) {
  std::ofstream out(file);
  if (!out) throw IoError("cannot write " + file.string());
  out << header << "\n";
  const int n = static_cast<int>(std::lround(L / g.dx()));
  IVec<2> node;
  node[1 - along] = static_cast<int>(std::lround((0.5 * L - g.origin()[1 - along]) / g.dx()));
  std::vector<double> line;
  for (int i = 0; i <= n; ++i) {
    node[along] = static_cast<int>(std::lround(-g.origin()[along] / g.dx())) + i;
    const Index k = g.node_index(node);
    line.push_back(k >= 0 ? g.velocity[k][comp] / U : 0.0);
    out << (i * g.dx()) / L << "," << line.back() << "\n";
  }
  return line;
}

//! RMS of (line - reference) at the points s (in [0, 1]); the line, sampled at s = i / n, is
//! interpolated linearly.
double rms_error(const std::vector<double>& line, const std::array<double, 17>& s, const std::array<double, 17>& ref) {
  const double n = static_cast<double>(line.size() - 1);
  double sum = 0.0;
  for (std::size_t j = 0; j < s.size(); ++j) {
    const std::size_t i = std::min(static_cast<std::size_t>(s[j] * n), line.size() - 2);
    const double w = s[j] * n - static_cast<double>(i);
    const double e = (1.0 - w) * line[i] + w * line[i + 1] - ref[j];
    sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(s.size()));
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
  // Walls half a cell thicker than the layer: the node rows at x = 0, x = L and y = 0 lie at
  // distance `layer` from the domain faces only up to round-off (dx = 1/24 put them outside).
  auto colliders = geometry::parse_colliders<2>(scene, domain.lo, domain.hi, layer + 0.5 * dx);
  // The lid: a sticky half-space moving along x (it stays in place: it slides along itself). Its
  // plane lies half a cell below y = L so that the top node row is inside it whatever the
  // rounding of L / cells (at y = L exactly, 24 cells left that row outside: no lid).
  colliders.add(geometry::Collider<2>(geometry::HalfSpace<2>(Vec<2>(0.0, L - 0.5 * dx), Vec<2>(0.0, -1.0)),
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
  runner.run(fluid.state, pipeline);

  // 3. Centre lines, extremes, steadiness, Ghia et al.
  const std::vector<double> u =
      write_centerline(runner.out_dir() / "centerline_u.csv", fluid.state.grid, 1, 0, L, U, "y,u");
  const std::vector<double> v =
      write_centerline(runner.out_dir() / "centerline_v.csv", fluid.state.grid, 0, 1, L, U, "x,v");
  const auto [u_min, u_max] = std::minmax_element(u.begin(), u.end());
  const auto [v_min, v_max] = std::minmax_element(v.begin(), v.end());
  const std::vector<double> kinetic = runner.history("kinetic_energy");
  const std::size_t last = kinetic.size() - 1, before = last - std::max<std::size_t>(1, last / 10);
  const double steadiness = kinetic[last] > 0.0 ? std::abs(kinetic[last] - kinetic[before]) / kinetic[last] : 0.0;
  std::vector<std::pair<std::string, double>> results = {
      {"reynolds", Re},  {"u_min", *u_min}, {"u_max", *u_max},
      {"v_min", *v_min}, {"v_max", *v_max}, {"kinetic_energy_change_last_10_percent", steadiness}};
  const auto table = std::find_if(ghia.begin(), ghia.end(), [&](const GhiaColumns& t) { return t.reynolds == Re; });
  if (table == ghia.end()) {
    runner.write_summary(results);
    if (!cl.check) return 0;
    std::fprintf(stderr, "check: reference values exist for reynolds = 100 and 1000 only\n");
    return 1;
  }
  const double ghia_u_min = *std::min_element(table->u.begin(), table->u.end());
  const double ghia_v_min = *std::min_element(table->v.begin(), table->v.end());
  const double ghia_v_max = *std::max_element(table->v.begin(), table->v.end());
  const double u_error = rms_error(u, ghia_y, table->u), v_error = rms_error(v, ghia_x, table->v);
  results.insert(results.end(), {{"ghia1982_u_min", ghia_u_min},
                                 {"ghia1982_v_max", ghia_v_max},
                                 {"ghia1982_v_min", ghia_v_min},
                                 {"ghia1982_u_rms_error", u_error},
                                 {"ghia1982_v_rms_error", v_error},
                                 {"ghia1982_rms_error", std::sqrt(0.5 * (u_error * u_error + v_error * v_error))}});
  runner.write_summary(results);
  if (!cl.check) return 0;
  const bool a = check_value("u_min", *u_min, ghia_u_min, 0.15 * std::abs(ghia_u_min));
  const bool b = check_value("v_max", *v_max, ghia_v_max, 0.15 * ghia_v_max);
  const bool c = check_value("v_min", *v_min, ghia_v_min, 0.15 * std::abs(ghia_v_min));
  return a && b && c ? 0 : 1;
}

int run3(const CommandLine&, const Config& scene) { scene.fail("dim", "lid_driven_cavity is a 2D scene (dim: 2)"); }

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "lid_driven_cavity", "Lid-driven cavity (LANS fluid)", run2, run3);
}
