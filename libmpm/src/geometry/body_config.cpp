#include <mpm/core/error.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

namespace mpm::geometry {

template <int dim>
int particles_per_cell(const Config& cfg) {
  const int ppc = cfg.integer("particles_per_cell", dim == 2 ? 4 : 8, 1, 1000);
  try {
    lattice_points_per_axis<dim>(ppc);
  } catch (const InputError& e) {
    cfg.fail("particles_per_cell", e.what());
  }
  return ppc;
}

template <int dim>
BodyParticles<dim> seed_body_shape(const Config& body, const SceneSettings<dim>& settings,
                                   const std::vector<std::string>& shapes) {
  const double dx = settings.dx;
  const int ppc = particles_per_cell<dim>(body);
  const double jitter = body.number("jitter", 0.0, Range::half_open(0.0, 1.0));
  const auto seed = static_cast<std::uint64_t>(body.integer("seed", 1, 0, 1 << 30));
  const std::string shape = body.choice("shape", "box", shapes);
  BodyParticles<dim> b{{}, particle_volume<dim>(dx, ppc)};
  // Seeding refuses a body too large for the memory (core/memory_budget.h): blame the body.
  const auto seeded = [&](const auto& seed_points) {
    try {
      return seed_points();
    } catch (const InputError& e) {
      body.fail("shape", e.what());
    }
  };
  if (shape == "box") {
    const Vec<dim> lo = body.vector<dim>("lo"), hi = body.vector<dim>("hi");
    b.x = seeded([&] { return seed_box<dim>(lo, hi, dx, ppc, jitter, seed); });
  } else if (shape == "sphere") {
    const Vec<dim> center = body.vector<dim>("center");
    const double radius = body.number("radius", Range::positive());
    b.x = seeded([&] { return seed_sphere<dim>(center, radius, dx, ppc, jitter, seed); });
  } else {
    const LevelSetShape<dim> level_set = parse_level_set<dim>(body);
    b.x = seeded([&] { return seed_level_set<dim>(level_set, dx, ppc, jitter, seed); });
  }
  if (b.x.empty()) body.fail("shape", "the body contains no particle at this resolution");
  // Blame the key that placed the body, so the message carries its file position and value.
  if (const OutsideDomain outside = first_outside_domain(settings, b.x); !outside.why.empty())
    body.fail(shape == "box"      ? (outside.below ? "lo" : "hi")
              : shape == "sphere" ? "center"
                                  : "file",
              "expected the body inside the domain, but " + outside.why);
  return b;
}

template int particles_per_cell<2>(const Config&);
template int particles_per_cell<3>(const Config&);
template BodyParticles<2> seed_body_shape(const Config&, const SceneSettings<2>&, const std::vector<std::string>&);
template BodyParticles<3> seed_body_shape(const Config&, const SceneSettings<3>&, const std::vector<std::string>&);

}  // namespace mpm::geometry
