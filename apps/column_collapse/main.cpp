// column_collapse: a dry granular column (Drucker-Prager sand) released against a back wall
// onto a rough (sticky) floor, in plane strain (dim: 2) or in a 3D channel (dim: 3).
//
//   column_collapse data/scenes/column_collapse.yaml
//   column_collapse data/scenes/column_collapse.yaml --set column.aspect_ratio=4 --out out/a4
//   column_collapse data/scenes/column_collapse_adaptive.yaml   (key adaptive: fine particles
//                                                                and cells along the free surface)
//
// profile.csv: the final deposit height per dx-wide slab.
// summary.json: runout L_inf (deposit front distance from the back wall), final_height,
// normalized_runout (L_inf - L0)/L0, duration (time until the kinetic energy falls below 1e-6
// of its peak), runout_law_error |normalized - law| / law, particles (the final count), and
// with the key reference_profile (a profile.csv of another run, e.g. a finer uniform grid)
// profile_error: the mean |h - h_reference| over both deposits' extent, over the column height.
// --check compares normalized_runout with the 2D runout law of Lube et al. 2005 (PRE 72,
// 041301): 1.2 a for a < 2.3, 1.9 a^(2/3) above, within +-25 % (data/reference/lube2005.md:
// the smoke run a = 1, 10 cells per width is 15 % below the law at friction angle 32 deg and
// 46 % below at 45 deg; +-50 % passed both). The default scene (a = 2, 20 cells) runs out 44 %
// beyond the law and fails this check: data/reference/lube2005.md.
#include <mpm/core/app.h>
#include <mpm/core/number_text.h>
#include <mpm/core/runner.h>
#include <mpm/cuda/device_pipeline.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>
#include <mpm/io/atomic_file.h>
#include <mpm/solid/solid_scene.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace mpm;

namespace {

double lube_runout_law(double a) { return a < 2.3 ? 1.2 * a : 1.9 * std::cbrt(a * a); }
//! --check: |normalized runout - law| <= runout_tolerance * law (measurements in lube2005.md).
constexpr double runout_tolerance = 0.25;

//! The deposit front [m]: the far edge of the contiguous run of dx-wide slabs, from the back
//! wall, that each hold at least half a layer of material (`layer` [m^dim] of initial
//! volume). Grains that broke away ahead of the deposit are not part of the runout, as in the
//! experiments.
template <int dim>
double deposit_front(const Particles<dim>& P, double dx, double layer) {
  std::vector<double> volume;
  for (std::size_t p = 0; p < P.size(); ++p) {
    const auto slab = static_cast<std::size_t>(std::max(0.0, P.x[p][0] / dx));
    if (slab >= volume.size()) volume.resize(slab + 1, 0.0);
    volume[slab] += P.volume0[p];
  }
  std::size_t slab = 0;
  while (slab < volume.size() && volume[slab] >= 0.5 * layer) ++slab;
  double front = 0.0;
  for (const Vec<dim>& x : P.x)
    if (x[0] < slab * dx) front = std::max(front, x[0]);
  return front;
}

//! The deposit's top per dx-wide slab from the back wall: (slab centre, height) [m].
template <int dim>
std::vector<std::pair<double, double>> height_profile(const Particles<dim>& P, double dx) {
  std::vector<double> top;
  for (const Vec<dim>& x : P.x) {
    const auto slab = static_cast<std::size_t>(std::max(0.0, x[0] / dx));
    if (slab >= top.size()) top.resize(slab + 1, 0.0);
    top[slab] = std::max(top[slab], x[1]);
  }
  std::vector<std::pair<double, double>> profile;
  for (std::size_t i = 0; i < top.size(); ++i) profile.emplace_back((static_cast<double>(i) + 0.5) * dx, top[i]);
  return profile;
}

//! A profile's height at x: linear between its points, the first point's before them, 0 past them.
double height_at(const std::vector<std::pair<double, double>>& profile, double x) {
  const auto after = std::lower_bound(profile.begin(), profile.end(), std::pair{x, -1e308});
  if (after == profile.end()) return 0.0;
  if (after == profile.begin()) return after->second;
  const auto& [x0, h0] = *(after - 1);
  return h0 + (after->second - h0) * (x - x0) / (after->first - x0);
}

//! Mean |h - h_reference| over the extent of both deposits, sampled at 2000 points.
double profile_difference(const std::vector<std::pair<double, double>>& profile,
                          const std::vector<std::pair<double, double>>& reference) {
  const double extent = std::max(profile.back().first, reference.back().first);
  constexpr int samples = 2000;
  double sum = 0.0;
  for (int i = 0; i < samples; ++i) {
    const double x = (i + 0.5) * extent / samples;
    sum += std::fabs(height_at(profile, x) - height_at(reference, x));
  }
  return sum / samples;
}

//! A profile.csv ("x,height" rows, x increasing) given by `key` of the scene.
std::vector<std::pair<double, double>> read_profile(const Config& scene, const std::string& key) {
  std::ifstream in(scene.input_file(key));
  if (!in) scene.fail(key, "cannot open the file");
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line != "x,height") scene.fail(key, "the file does not start with the header 'x,height'");
  std::vector<std::pair<double, double>> profile;
  for (int row = 2; std::getline(in, line); ++row) {
    if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF line ends
    if (line.empty()) continue;
    double x = 0.0, h = 0.0;
    char comma = 0;
    std::istringstream fields(line);
    if (!(fields >> x >> comma >> h) || comma != ',' || !std::isfinite(x) || !std::isfinite(h) ||
        (!profile.empty() && x <= profile.back().first))
      scene.fail(key, "line " + std::to_string(row) + " is not 'x,height' with finite numbers and x increasing: '" +
                          line + "'");
    profile.emplace_back(x, h);
  }
  if (profile.empty()) scene.fail(key, "the file has no profile rows");
  return profile;
}

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  // 1. The column and the domain derived from it: back wall at x = 0, floor at y = 0.
  const Config column = scene.child("column");
  const double L0 = column.number("width", Range::positive());
  const double a = column.number("aspect_ratio", Range{0.0, 100.0, true, false});
  const double H0 = a * L0;
  const double dx = L0 / column.integer("cells_per_width", 20, 2, 4096);
  const double length =
      column.number("domain_length", L0 * (1.0 + 1.5 * lube_runout_law(a)) + 4 * dx, Range{L0, 1e308, true, false});
  const double depth = dim == 3 ? column.number("depth", L0, Range::positive()) : 0.0;
  // Walls at x = 0, y = 0, z = 0; on an adaptive grid they act on coarse nodes (dx 2^(levels-1)).
  const double layer = wall_layer(parse_kernel(scene), dx * (1 << (adaptive::levels_of(scene) - 1)));
  DerivedDomain<dim> domain{Vec<dim>::Constant(-layer), Vec<dim>::Zero(), dx};
  domain.hi[0] = length + layer;
  domain.hi[1] = H0 + 2 * layer;
  if constexpr (dim == 3) domain.hi[2] = depth + layer;

  // 2. Settings, the sand, the walls (all validated before anything is written).
  SceneSettings<dim> settings = parse_scene_settings<dim>(scene, domain);
  std::vector<Material<dim>> sand = {parse_material<dim>(scene.child("material"))};
  auto colliders = geometry::parse_colliders<dim>(scene, domain.lo, domain.hi, layer);
  solid::SolidScene<dim> solid = solid::make_solid_scene(settings, sand, colliders);
  solid::read_adaptive_key(solid, scene);
  const int ppc = geometry::particles_per_cell<dim>(column);
  Vec<dim> hi = Vec<dim>::Zero();
  hi[0] = L0;
  hi[1] = H0;
  if constexpr (dim == 3) hi[2] = depth;
  std::vector<Vec<dim>> seeded;
  try {
    seeded = geometry::seed_box<dim>(Vec<dim>::Zero(), hi, dx, ppc, 0.0, 1);
  } catch (const InputError& e) {
    column.fail("cells_per_width", e.what());  // the key that sets dx (too large for the memory)
  }
  solid::add_particles<dim>(solid, seeded, geometry::particle_volume<dim>(dx, ppc), std::uint16_t{0}, Vec<dim>::Zero(),
                            "column");
  const cuda::Device device = cuda::parse_device(scene);
  std::optional<std::vector<std::pair<double, double>>> reference;
  if (scene.has("reference_profile")) reference = read_profile(scene, "reference_profile");
  scene.reject_unknown_keys();

  // 3. Run (on the CPU, or on a GPU with `device: cuda`).
  auto pipeline = cuda::make_solid_pipeline(solid, device, scene);
  Runner<dim> runner("column_collapse", cl, scene, settings);
  runner.set_elastic_energy([&](const MpmState<dim>& s) { return solid::elastic_energy(s, solid.materials); });
  runner.run(solid.state, pipeline);

  // 4. Results; the duration from the kinetic energy of every frame (restarts included).
  const std::vector<double> time = runner.history("time"), kinetic = runner.history("kinetic_energy");
  double peak = 0.0, duration = settings.end_time;
  bool at_rest = false;
  for (std::size_t f = 0; f < time.size() && !at_rest; ++f) {
    peak = std::max(peak, kinetic[f]);
    at_rest = peak > 0.0 && kinetic[f] < 1e-6 * peak;
    if (at_rest) duration = time[f];
  }
  const int k = geometry::lattice_points_per_axis<dim>(ppc);
  const double row = dim == 2 ? k : k * k * depth / dx;  // particles per lattice row of a slab
  const double runout = deposit_front(solid.state.particles, dx, row * geometry::particle_volume<dim>(dx, ppc));
  const std::vector<std::pair<double, double>> profile = height_profile(solid.state.particles, dx);
  std::string csv = "x,height\n";
  for (const auto& [x, h] : profile) csv += exact_number_text(x) + "," + exact_number_text(h) + "\n";
  io::write_file_atomically(runner.out_dir() / "profile.csv", csv);
  double height = 0.0;
  for (const Vec<dim>& x : solid.state.particles.x) height = std::max(height, x[1]);
  const double normalized = (runout - L0) / L0;
  std::vector<std::pair<std::string, double>> results{
      {"runout", runout},
      {"final_height", height},
      {"normalized_runout", normalized},
      {"duration", duration},
      {"at_rest", at_rest ? 1.0 : 0.0},
      {"particles", static_cast<double>(solid.state.particles.size())},
      {"runout_law_lube2005", lube_runout_law(a)},
      {"runout_law_error", std::fabs(normalized - lube_runout_law(a)) / lube_runout_law(a)}};
  if (reference) results.emplace_back("profile_error", profile_difference(profile, *reference) / H0);
  runner.write_summary(results);
  if (cl.check) {
    const double law = lube_runout_law(a);
    return check_value("normalized_runout", normalized, law, runout_tolerance * law) ? 0 : 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "column_collapse", "Dry granular column collapse (Drucker-Prager)", run<2>, run<3>);
}
