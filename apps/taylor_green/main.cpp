// taylor_green: the decaying Taylor-Green vortex in the periodic square [0, 2 pi L)^2
// (Taylor & Green 1937; data/reference/taylor_green.md), k = 1 / L, nu = mu / rho:
//   u = U sin(kx) cos(ky) e^{-2 nu k^2 t},   v = -U cos(kx) sin(ky) e^{-2 nu k^2 t},
//   p = rho U^2 / 4 (cos 2kx + cos 2ky) e^{-4 nu k^2 t},   KE(t) = KE(0) e^{-4 nu k^2 t}.
//
//   taylor_green data/scenes/taylor_green.yaml
//   taylor_green data/scenes/taylor_green.yaml --set vortex.resolution=64 --set pressure.solver=cholmod
//
// Particles start with the exact velocity and APIC C_p = grad u(x_p) (exact for the affine part).
// diagnostics.csv adds l2_velocity_error at every output time (kinetic_energy is a standard
// column). summary.json: l2_velocity_error (volume-weighted L2 norm over the particles of v_p - u(x_p, T), relative to
// the L2 norm of u(., T)) and kinetic_energy_decay_error (|(KE(T)/KE(0)) / e^{-4 nu k^2 T} - 1|)
// at the final time T. Steps are equal (see run_2d), so dt ~ dx. --check: l2_velocity_error
// below 2 / resolution (first order: measured 0.080, 0.046, 0.025, 0.0125 at 16, 32, 64, 128
// cells, docs/accuracy.md).
#include <fluid/scene/fluid_scene.h>

#include <mpm/core/app.h>
#include <mpm/core/runner.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>
#include <cmath>
#include <numbers>

using namespace mpm;

namespace {

struct Vortex {
  double U, k, nu;  // [m/s], [1/m], [m^2/s]
  double decay(double t) const { return std::exp(-2.0 * nu * k * k * t); }
  Vec<2> velocity(const Vec<2>& x, double t) const {
    return U * decay(t) * Vec<2>(std::sin(k * x[0]) * std::cos(k * x[1]), -std::cos(k * x[0]) * std::sin(k * x[1]));
  }
  //! grad u: row = velocity component, column = derivative.
  Mat<2> gradient(const Vec<2>& x, double t) const {
    const double cc = std::cos(k * x[0]) * std::cos(k * x[1]), ss = std::sin(k * x[0]) * std::sin(k * x[1]);
    Mat<2> G;
    G << cc, -ss, ss, -cc;
    return U * k * decay(t) * G;
  }
};

//! sqrt(sum V_p |v_p - u(x_p, t)|^2) / sqrt(sum V_p |u(x_p, t)|^2).
double l2_velocity_error(const MpmState<2>& s, const Vortex& vortex) {
  double error = 0.0, norm = 0.0;
  for (std::size_t p = 0; p < s.particles.size(); ++p) {
    const Vec<2> exact = vortex.velocity(s.particles.x[p], s.time);
    error += s.particles.volume0[p] * (s.particles.v[p] - exact).squaredNorm();
    norm += s.particles.volume0[p] * exact.squaredNorm();
  }
  return std::sqrt(error / norm);
}

double kinetic_energy(const MpmState<2>& s) {
  double e = 0.0;
  for (std::size_t p = 0; p < s.particles.size(); ++p) e += 0.5 * s.particles.mass[p] * s.particles.v[p].squaredNorm();
  return e;
}

int run_2d(const CommandLine& cl, const Config& scene) {
  // 1. The periodic square [0, 2 pi L)^2 and the vortex.
  const Config keys = scene.child("vortex");
  const double L = keys.number("length", 1.0, Range::positive());
  const int cells = keys.integer("resolution", 32, 4, 4096);
  const int ppc = geometry::particles_per_cell<2>(keys);
  const double side = 2.0 * std::numbers::pi * L, dx = side / cells;
  SceneSettings<2> settings =
      parse_scene_settings<2>(scene, DerivedDomain<2>{Vec<2>::Zero(), Vec<2>::Constant(side), dx});
  if (!settings.periodic[0] || !settings.periodic[1]) scene.fail("periodic", "the vortex needs periodic: [true, true]");
  const fluid::FluidMaterial material = fluid::parse_fluid_material(scene.child("fluid"));
  const Vortex vortex{keys.number("U", 1.0, Range::positive()), 1.0 / L, material.viscosity / material.density};
  // Equal steps dt = T / n, n = ceil(T U / (cfl dx)) (dt ~ dx; the speed never exceeds U): the
  // projection removes the divergence that an advection step creates one step later, so the
  // final velocity lacks the pressure impulse of the last step, an error ~ that step's size,
  // which a last step clipped to the end time would make erratic.
  settings.max_dt =
      std::min(settings.max_dt, settings.end_time / std::ceil(settings.end_time * vortex.U / (settings.cfl * dx)));

  // 2. Particles with the exact velocity and its gradient as C.
  fluid::FluidScene<2> water = fluid::make_fluid_scene(settings, material, fluid::parse_pressure_settings(scene), {});
  fluid::add_fluid_particles<2>(water, geometry::seed_box<2>(Vec<2>::Zero(), Vec<2>::Constant(side), dx, ppc, 0.0, 1),
                                geometry::particle_volume<2>(dx, ppc), Vec<2>::Zero(), "vortex");
  Particles<2>& P = water.state.particles;
  for (std::size_t p = 0; p < P.size(); ++p) {
    P.v[p] = vortex.velocity(P.x[p], 0.0);
    P.C[p] = vortex.gradient(P.x[p], 0.0);
  }
  scene.reject_unknown_keys();

  // 3. Run.
  auto pipeline = fluid::make_fluid_pipeline(water);
  Runner<2> runner("taylor_green", cl, scene, settings);
  runner.add_column("l2_velocity_error", [&](const MpmState<2>& s) { return l2_velocity_error(s, vortex); });
  const double energy0 = kinetic_energy(water.state);
  runner.run(water.state, pipeline);

  // 4. Errors at the final time.
  const double error = l2_velocity_error(water.state, vortex);
  const double T = water.state.time;
  const double decay_error = std::abs(kinetic_energy(water.state) / energy0 / std::pow(vortex.decay(T), 2) - 1.0);
  runner.write_summary({{"l2_velocity_error", error},
                        {"kinetic_energy_decay_error", decay_error},
                        {"final_time", T},
                        {"exact_energy_ratio", std::pow(vortex.decay(T), 2)}});
  if (cl.check) return check_value("l2_velocity_error", error, 0.0, 2.0 / cells) ? 0 : 1;
  return 0;
}

int run_3d(const CommandLine&, const Config& scene) { scene.fail("dim", "the Taylor-Green vortex is 2D (dim: 2)"); }

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "taylor_green", "Decaying Taylor-Green vortex (periodic LANS fluid)", run_2d,
                       run_3d);
}
