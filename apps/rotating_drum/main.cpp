// rotating_drum: sand in a turning drum (paper Fig. 11): a hollow sphere collider (a disk in
// 2D) with angular_velocity drags the sand up its wall until it avalanches down the free
// surface. On an adaptive grid with resampling the surface keeps fine particles however the
// sand tumbles; without resampling the coarse particles of the interior are carried up to the
// surface and stay coarse there.
//
//   rotating_drum data/scenes/rotating_drum.yaml
//
// diagnostics.csv adds surface_fine_fraction (the volume fraction of the particles in the
// free-surface layer, one finest cell deep, that are of the finest type; 1 on a uniform grid)
// and repose_angle (the slope of the free surface within half a radius of the drum's axis
// [deg], a least-squares line through the surface particles there). summary.json: their means
// over the second half of the run, and the final particle count. --check asserts a mean
// surface_fine_fraction >= 0.9.
#include <mpm/adaptive/particle_levels.h>
#include <mpm/adaptive/resampling.h>
#include <mpm/core/app.h>
#include <mpm/core/runner.h>
#include <mpm/solid/solid_scene.h>

#include <cmath>
#include <numbers>

using namespace mpm;

namespace {

//! Each particle's Manhattan distance from the free surface [m], on cells of the finest dx.
template <int dim>
std::vector<double> surface_distance(const MpmState<dim>& s, const SceneSettings<dim>& settings) {
  const Particles<dim>& P = s.particles;
  if (s.adaptive)
    return adaptive::surface_distance(s.adaptive->tree(), P.x,
                                      P.template channel<std::uint16_t>(adaptive::kParticleLevel),
                                      s.adaptive->points_per_axis(), 4 * settings.dx);
  // A uniform grid is a one-level tree; its particles have type 0 (k = 2 per axis).
  IVec<dim> cells;
  for (int a = 0; a < dim; ++a)
    cells[a] = static_cast<int>(std::ceil((settings.domain_hi[a] - settings.domain_lo[a]) / settings.dx));
  const adaptive::CellTree<dim> flat(settings.domain_lo, cells, settings.dx, 1);
  return adaptive::surface_distance(flat, P.x, std::vector<std::uint16_t>(P.size(), 0), 2, 4 * settings.dx);
}

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  solid::SolidScene<dim> solid = solid::load_solid_scene<dim>(scene);
  scene.reject_unknown_keys();
  const geometry::Collider<dim>* drum = nullptr;
  for (const auto& c : solid.colliders.colliders())
    if (c.hollow() && std::holds_alternative<geometry::Sphere<dim>>(c.shape())) drum = &c;
  if (!drum) scene.fail("colliders", "the scene needs a hollow sphere collider (the drum)");
  const auto& shape = std::get<geometry::Sphere<dim>>(drum->shape());
  const int finest = solid.state.adaptive ? solid.state.adaptive->tree().finest() : 0;

  auto pipeline = solid::make_solid_pipeline(solid);
  Runner<dim> runner("rotating_drum", cl, scene, solid.settings);
  runner.set_elastic_energy([&](const MpmState<dim>& s) { return solid::elastic_energy(s, solid.materials); });
  runner.add_column("surface_fine_fraction", [&](const MpmState<dim>& s) {
    const std::vector<double> d = surface_distance(s, solid.settings);
    const std::vector<std::uint16_t>* level =
        s.particles.template find_channel<std::uint16_t>(adaptive::kParticleLevel);
    double fine = 0.0, all = 0.0;
    for (std::size_t p = 0; p < d.size(); ++p)
      if (d[p] < solid.settings.dx) {
        all += s.particles.volume0[p];
        if (!level || (*level)[p] == finest) fine += s.particles.volume0[p];
      }
    return all > 0.0 ? fine / all : 1.0;
  });
  runner.add_column("repose_angle", [&](const MpmState<dim>& s) {
    // Surface particles within half a radius of the axis, off the drum wall: the free surface.
    const std::vector<double> d = surface_distance(s, solid.settings);
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t p = 0; p < d.size(); ++p) {
      const Vec<dim> r = s.particles.x[p] - shape.center();
      if (d[p] >= solid.settings.dx || std::abs(r[0]) > 0.5 * shape.radius()) continue;
      if (shape.radius() - r.norm() < 2 * solid.settings.dx) continue;
      n += 1;
      sx += r[0];
      sy += r[1];
      sxx += r[0] * r[0];
      sxy += r[0] * r[1];
    }
    const double det = n * sxx - sx * sx;
    return n > 2 && det > 0.0 ? std::atan((n * sxy - sx * sy) / det) * 180.0 / std::numbers::pi : 0.0;
  });
  runner.run(solid.state, pipeline);

  auto late_mean = [&](const std::string& column) {
    const std::vector<double> h = runner.history(column);
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t f = h.size() / 2; f < h.size(); ++f, ++count) sum += h[f];
    return count ? sum / static_cast<double>(count) : 0.0;
  };
  const double fine = late_mean("surface_fine_fraction");
  runner.write_summary({{"surface_fine_fraction", fine},
                        {"repose_angle", late_mean("repose_angle")},
                        {"particles", static_cast<double>(solid.state.particles.size())}});
  if (cl.check) return check_value("surface_fine_fraction", fine, 1.0, 0.1) ? 0 : 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "rotating_drum", "Sand in a turning drum (adaptive resampling)", run<2>, run<3>);
}
