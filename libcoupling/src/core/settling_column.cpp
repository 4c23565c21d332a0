#include <coupling/settling_column.h>
#include <mpm/core/error.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>
#include <cmath>

namespace coupling {

double SettlingColumn::stokes_velocity() const {
  return drag::parameters(drag).stokes_velocity(sediment_density, gravity);
}

double SettlingColumn::hindered_velocity() const {
  return drag::settling_velocity(drag, 1.0 - volume_fraction, sediment_density, gravity);
}

double SettlingColumn::terminal_velocity() const {
  const drag::DragParameters& p = drag::parameters(drag);
  const auto drag_force = [&](double v) { return p.stokes_scale() * drag::schiller_naumann_cd_re(reynolds(v)) * v; };
  return drag::root_of_increasing(drag_force, (sediment_density - fluid_density) * gravity, stokes_velocity());
}

double SettlingColumn::richardson_zaki_velocity() const {
  const double v_t = terminal_velocity();
  return std::pow(1.0 - volume_fraction, drag::richardson_zaki_exponent(reynolds(v_t))) * v_t;
}

double SettlingColumn::reynolds(double velocity) const {
  const drag::DragParameters& p = drag::parameters(drag);
  return fluid_density * std::abs(velocity) * p.diameter / p.viscosity;
}

template <int dim>
SettlingScene<dim> load_settling_column(const mpm::Config& scene) {
  using mpm::Range;
  const mpm::Config c = scene.child("column");
  SettlingColumn col;
  col.width = c.number("width", Range::positive());
  col.height = c.number("height", Range::positive());
  col.suspension_height = c.number("suspension_height", Range{0.0, col.height, true, false});
  const int cells = c.integer("cells_per_width", 8, 2, 4096);
  const double dx = col.width / cells;
  const int ppc = mpm::geometry::particles_per_cell<dim>(c);

  const fluid::FluidMaterial water = fluid::parse_fluid_material(scene.child("fluid"));
  const fluid::FluidSolverSettings liquid = fluid::parse_fluid_solver(scene.child("fluid"));
  col.fluid_density = water.density;
  col.drag = drag::parse_drag_law(scene);
  const mpm::Config s = scene.child("sediment");
  SedimentPhase<dim> sand;
  sand.density = s.number("density", Range{water.density, 1e308, true, false});
  col.sediment_density = sand.density;
  col.volume_fraction = s.number("volume_fraction", Range::open(0.0, 1.0 - sand.min_fluid_fraction));

  const double layer = mpm::wall_layer(mpm::parse_kernel(scene), dx);
  mpm::DerivedDomain<dim> domain{mpm::Vec<dim>::Constant(-layer), mpm::Vec<dim>::Constant(col.width + layer), dx};
  domain.hi[1] = col.height + layer;
  mpm::SceneSettings<dim> settings = mpm::parse_scene_settings<dim>(scene, domain);
  for (int a = 0; a < dim; ++a)
    if (settings.periodic[a]) scene.fail("periodic", "the settling column is closed; it has no periodic axes");
  col.gravity = settings.gravity.norm();
  auto colliders = mpm::geometry::parse_colliders<dim>(scene, domain.lo, domain.hi, layer);
  mpm::verify<mpm::InputError>(colliders.walls().has_value(),
                               scene.path() + ": the settling column needs `walls` (contact: sticky) to be closed");

  SettlingScene<dim> out{col, make_coupled_scene<dim>(settings, std::move(colliders), water,
                                                      fluid::parse_pressure_settings(scene), sand, col.drag, liquid)};
  mpm::Vec<dim> top = mpm::Vec<dim>::Constant(col.width), mid = top;
  top[1] = col.height;
  mid[1] = col.suspension_height;
  const double volume = mpm::geometry::particle_volume<dim>(dx, ppc);
  const mpm::Vec<dim> rest = mpm::Vec<dim>::Zero();
  const auto suspension = mpm::geometry::seed_box<dim>(mpm::Vec<dim>::Zero(), mid, dx, ppc, 0.0, 1);
  add_fluid_particles(out.scene, suspension, volume, 1.0 - col.volume_fraction, rest, "column");
  add_sediment_particles(out.scene, suspension, col.volume_fraction * volume, rest, "column");
  mpm::Vec<dim> above = mpm::Vec<dim>::Zero();
  above[1] = col.suspension_height;
  if (col.suspension_height < col.height)
    add_fluid_particles(out.scene, mpm::geometry::seed_box<dim>(above, top, dx, ppc, 0.0, 1), volume, 1.0, rest,
                        "column");
  out.scene.fluid_solver->start_at_rest(out.scene.state.fluid.particles, out.scene.settings);
  return out;
}

template <int dim>
double mean_sediment_velocity(const CoupledState<dim>& state, double floor_margin) {
  const auto& P = state.sediment.particles;
  double sum = 0.0;
  int count = 0;
  for (std::size_t p = 0; p < P.size(); ++p)
    if (P.x[p][1] > floor_margin) {
      sum += P.v[p][1];
      ++count;
    }
  return count > 0 ? sum / count : 0.0;
}

template <int dim>
double suspension_top(const CoupledState<dim>& state, const SettlingColumn& column, double wall_margin) {
  double top = 0.0;
  for (const mpm::Vec<dim>& x : state.sediment.particles.x) {
    bool inside = true;
    for (int a = 0; a < dim; ++a)
      if (a != 1) inside = inside && x[a] > wall_margin && x[a] < column.width - wall_margin;
    if (inside) top = std::max(top, x[1]);
  }
  return top;
}

#define SETTLING_COLUMN(dim)                                                 \
  template SettlingScene<dim> load_settling_column<dim>(const mpm::Config&); \
  template double mean_sediment_velocity(const CoupledState<dim>&, double);  \
  template double suspension_top(const CoupledState<dim>&, const SettlingColumn&, double);
SETTLING_COLUMN(2)
SETTLING_COLUMN(3)

}  // namespace coupling
