// The implicit solid step (stage implicit_update): its gradient and Hessian-vector product
// against finite differences of the incremental potential for every elastic model, also with
// flat and inverted particles and with particle domains (enriched corners among the unknowns);
// Newton's decrease of the potential; momentum conservation to the solver tolerance; walls
// inside the solve; bad input.
#include <doctest/doctest.h>

#include <mpm/constitutive/elastic_model.h>
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/solve/vector_space.h>
#include <mpm/core/transfer.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>
#include <mpm/solid/stages/domain_transfer.h>
#include <mpm/solid/stages/implicit_update.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace mpm;

namespace {

template <int dim>
std::string scene_yaml(const std::string& model, double youngs, bool walls) {
  const std::string lo = dim == 2 ? "[0, 0]" : "[0, 0, 0]", hi = dim == 2 ? "[1, 1]" : "[1, 1, 1]";
  const std::string blo = dim == 2 ? "[0.3, 0.12]" : "[0.3, 0.12, 0.3]",
                    bhi = dim == 2 ? "[0.6, 0.4]" : "[0.6, 0.4, 0.5]";
  const std::string g = dim == 2 ? "[0, -9.81]" : "[0, -9.81, 0]";
  return "dim: " + std::to_string(dim) + "\ndomain: {lo: " + lo + ", hi: " + hi + "}\ngrid: {dx: 0.1}\n" +
         "time: {end: 0.1}\ngravity: " + g + "\nsolver: implicit\n" + (walls ? "walls: {contact: separate}\n" : "") +
         "materials: [{name: m, density: 1000, youngs_modulus: " + std::to_string(youngs) +
         ", poisson_ratio: 0.3, elasticity: " + model + "}]\n" + "bodies: [{shape: box, lo: " + blo + ", hi: " + bhi +
         ", material: m}]\n";
}

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

// A scene with deformed particles (some nearly flat and inverted when `extreme`), sorted and
// transferred: the state the implicit stage starts from.
template <int dim>
solid::SolidScene<dim> deformed_scene(const std::string& model, bool extreme, std::mt19937& rng, bool walls = true) {
  solid::SolidScene<dim> scene = solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>(model, 1e5, walls)));
  MpmState<dim>& s = scene.state;
  std::vector<Mat<dim>>& F = solid::elastic_F(s.particles);
  for (std::size_t p = 0; p < F.size(); ++p) {
    F[p] = Mat<dim>::Identity() + 0.2 * Mat<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); });
    if (extreme && p % 3 == 0) {  // flat (0.02) or inverted (-0.3) along a random direction
      const Vec<dim> n = Vec<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); }).normalized();
      F[p] = (Mat<dim>::Identity() + ((p % 2 ? 0.02 : -0.3) - 1.0) * n * n.transpose()) * F[p];
    }
    s.particles.v[p] = Vec<dim>::NullaryExpr([&] { return uniform(rng, -0.5, 0.5); });
  }
  s.dt = 2e-3;
  sort_into_buckets(s.particles, s.kernel, s.grid, s.buckets, "test");
  particles_to_grid(s.particles, s.buckets, s.kernel, s.transfer, s.grid);
  momentum_to_velocity(s.grid, s.transfer);
  return scene;
}

// A scene with particle domains whose corners are moved at random (F from the corners), with
// the corners of the particles with K(F) <= 0.9 enriched, transferred to the grid: transitional
// particles, enriched and grid-only corners side by side.
template <int dim>
solid::SolidScene<dim> domain_scene(const std::string& model, std::mt19937& rng, bool walls = true,
                                    bool velocities = true) {
  solid::SolidScene<dim> scene = solid::load_solid_scene<dim>(
      Config::parse(scene_yaml<dim>(model, 1e5, walls), "<string>",
                    {"particle_domains=true", "domain_enrichment=0.9", "transfer.scheme=flip", "grid.dx=0.15"}));
  MpmState<dim>& s = scene.state;
  domains::ParticleDomains<dim>& d = *s.domains;
  for (Vec<dim>& x : d.x) x += 0.3 * s.grid.dx() * Vec<dim>::NullaryExpr([&] { return uniform(rng, -0.2, 0.2); });
  std::vector<Mat<dim>>& F = solid::elastic_F(s.particles);
  for (std::size_t p = 0; p < F.size(); ++p) {
    F[p] = d.deformation(p);
    s.particles.v[p] = Vec<dim>::NullaryExpr([&] { return uniform(rng, -0.5, 0.5); });
  }
  s.dt = 2e-3;
  domains::mark_enrichment(d, F);
  stages::DomainsToGrid<dim>(scene.materials).run(s);
  if (velocities) momentum_to_velocity(s.grid, s.transfer);
  return scene;
}

//! v^n of every unknown: the grid's velocities, then the enriched corners' p_alpha / m_alpha.
template <int dim>
std::vector<Vec<dim>> start_velocities(const MpmState<dim>& s, const std::vector<double>& mass) {
  std::vector<Vec<dim>> v(mass.size(), Vec<dim>::Zero());
  for (std::size_t k = 0; k < mass.size(); ++k)
    if (mass[k] > 0.0)
      v[k] = k < s.grid.node_storage() ? s.grid.velocity[k]
                                       : Vec<dim>(s.domains->momentum[k - s.grid.node_storage()] / mass[k]);
  return v;
}

template <int dim>
std::vector<Vec<dim>> random_unknowns(const std::vector<double>& mass, std::mt19937& rng, double scale) {
  std::vector<Vec<dim>> v(mass.size(), Vec<dim>::Zero());
  for (std::size_t k = 0; k < v.size(); ++k)
    if (mass[k] > 0.0) v[k] = scale * Vec<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); });
  return v;
}

template <int dim>
std::vector<Vec<dim>> axpy(const std::vector<Vec<dim>>& x, double a, const std::vector<Vec<dim>>& y) {
  std::vector<Vec<dim>> r(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) r[k] = x[k] + a * y[k];
  return r;
}

template <int dim>
double distance(const std::vector<Vec<dim>>& a, const std::vector<Vec<dim>>& b) {
  double d = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) d += (a[k] - b[k]).squaredNorm();
  return std::sqrt(d);
}

template <int dim>
Vec<dim> momentum(const std::vector<double>& mass, const std::vector<Vec<dim>>& v) {
  Vec<dim> p = Vec<dim>::Zero();
  for (std::size_t k = 0; k < v.size(); ++k) p += mass[k] * v[k];
  return p;
}

template <int dim>
stages::ImplicitUpdate<dim> implicit_stage(const solid::SolidScene<dim>& scene,
                                           stages::ImplicitSettings settings = {}) {
  return stages::ImplicitUpdate<dim>(scene.materials, scene.colliders, settings);
}

// The gradient against central differences of E, the Hessian-vector product against
// differences of the gradient, the definite product symmetric and positive on its stiffness
// part (and, with `indefinite`, different from the exact one).
template <int dim>
void check_derivatives(const solid::SolidScene<dim>& scene, std::mt19937& rng, bool indefinite) {
  const MpmState<dim>& s = scene.state;
  stages::ImplicitUpdate<dim> stage = implicit_stage(scene);
  const std::vector<double> mass = stage.unknown_mass(s);
  const std::vector<Vec<dim>> predicted = start_velocities(s, mass);
  const std::vector<Vec<dim>> v = axpy(predicted, 1.0, random_unknowns<dim>(mass, rng, 0.3));
  const std::vector<Vec<dim>> dv = random_unknowns<dim>(mass, rng, 1.0);
  const double h = 1e-6;

  // dE/dv . dv by central differences.
  std::vector<Vec<dim>> g;
  stage.gradient(s, v, predicted, g);
  const double dE =
      (stage.potential(s, axpy(v, h, dv), predicted) - stage.potential(s, axpy(v, -h, dv), predicted)) / (2 * h);
  CHECK(solve::dot(g, dv) == doctest::Approx(dE).epsilon(1e-6));

  // (M + dt^2 K) dv against differences of the gradient, compared on the stiffness part
  // dt^2 K dv alone (M dv is exact on both sides and would hide an error in K).
  std::vector<Vec<dim>> g_plus, g_minus, Hdv;
  stage.gradient(s, axpy(v, h, dv), predicted, g_plus);
  stage.gradient(s, axpy(v, -h, dv), predicted, g_minus);
  std::vector<Vec<dim>> fd(g.size()), Mdv(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) {
    Mdv[k] = mass[k] * dv[k];
    fd[k] = (g_plus[k] - g_minus[k]) / (2 * h) - Mdv[k];
  }
  stage.hessian_product(s, v, dv, Hdv, false);
  const std::vector<Vec<dim>> Kdv = axpy(Hdv, -1.0, Mdv);
  REQUIRE(solve::dot(fd, fd) > 0.0);
  CHECK(distance(Kdv, fd) <= 1e-5 * std::sqrt(solve::dot(fd, fd)));

  // The definite product is symmetric and its stiffness part positive semi-definite:
  // w . H dv = dv . H w and dv . (H - M) dv >= 0. With flat and inverted particles the
  // exact stiffness is indefinite, and the fix changes the product.
  const std::vector<Vec<dim>> w = random_unknowns<dim>(mass, rng, 1.0);
  std::vector<Vec<dim>> Hw, definite;
  stage.hessian_product(s, v, dv, definite, true);
  stage.hessian_product(s, v, w, Hw, true);
  CHECK(solve::dot(w, definite) == doctest::Approx(solve::dot(dv, Hw)).epsilon(1e-10));
  const std::vector<Vec<dim>> Kdv_definite = axpy(definite, -1.0, Mdv);
  CHECK(solve::dot(dv, Kdv_definite) >=
        -1e-10 * std::sqrt(solve::dot(Kdv_definite, Kdv_definite) * solve::dot(dv, dv)));
  if (indefinite) CHECK(distance(Kdv_definite, Kdv) > 1e-3 * std::sqrt(solve::dot(Kdv, Kdv)));

  // The Jacobi diagonal is that of the definite operator: e . H e for unit vectors e (every
  // 5th node with mass and every enriched corner, each component; its stiffness part is >= 0,
  // so no clamp acts).
  std::vector<Vec<dim>> diagonal, e(mass.size(), Vec<dim>::Zero()), He;
  stage.preconditioner_diagonal(s, v, diagonal, true);
  REQUIRE(diagonal.size() == mass.size());
  int checked = 0, corners = 0;
  for (std::size_t k = 0; k < mass.size(); ++k) {
    const bool corner = k >= s.grid.node_storage();
    if (mass[k] <= 0.0 || (!corner && k % 5 != 0)) continue;
    corners += corner;
    for (int a = 0; a < dim; ++a) {
      e[k] = Vec<dim>::Unit(a);
      stage.hessian_product(s, v, e, He, true);
      CHECK(diagonal[k][a] == doctest::Approx(He[k][a]).epsilon(1e-10));
      e[k].setZero();
      ++checked;
    }
  }
  CHECK(checked > 0);
  if (s.domains) CHECK(corners > 0);
}

// One implicit step solved to 1e-10: the merit decreases every Newton iteration, up to the
// round-off of E that the line search tolerates when the residual falls (1e-9 |E|).
template <int dim>
void converged_step(solid::SolidScene<dim>& scene) {
  stages::ImplicitSettings settings;
  settings.tolerance = 1e-10;
  settings.linear_tolerance = 1e-6;
  stages::ImplicitUpdate<dim> stage = implicit_stage(scene, settings);
  stage.run(scene.state);
  const std::vector<double>& E = stage.merit_history();
  REQUIRE(E.size() >= 2);
  for (std::size_t n = 1; n < E.size(); ++n) CHECK(E[n] <= E[n - 1] + 1e-9 * std::abs(E[n - 1]));
  CHECK(E.back() < E.front());
  CHECK(stage.diagnostics()[2].value <= 1e-10);  // newton_residual within tolerance
}

}  // namespace

TEST_CASE_TEMPLATE("implicit step: gradient and Hessian-vector product against finite differences", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  for (const std::string& model : constitutive::elastic_model_names()) {
    for (const bool extreme : {false, true}) {
      INFO(model, " in ", dim, "D", extreme ? ", flat and inverted particles" : "");
      std::mt19937 rng(14);
      check_derivatives(deformed_scene<dim>(model, extreme, rng), rng, extreme);
    }
  }
}

TEST_CASE_TEMPLATE("implicit step with particle domains: derivatives through corners and enriched corners", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  for (const std::string& model : constitutive::elastic_model_names()) {
    INFO(model, " in ", dim, "D");
    std::mt19937 rng(5);
    const solid::SolidScene<dim> scene = domain_scene<dim>(model, rng);
    const domains::ParticleDomains<dim>& d = *scene.state.domains;
    // Some corners enriched, some not: both kinds of unknowns and transitional particles.
    REQUIRE(d.enriched_particles > 0);
    REQUIRE(d.enriched_particles < d.particle_count());
    check_derivatives(scene, rng, false);
  }
}

TEST_CASE_TEMPLATE("implicit step: Newton lowers the potential every iteration and conserves momentum", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  for (const std::string& model : constitutive::elastic_model_names()) {
    INFO(model, " in ", dim, "D");
    std::mt19937 rng(2013);
    // No walls and no gravity: only internal forces act, which sum to zero on the grid.
    solid::SolidScene<dim> scene = deformed_scene<dim>(model, false, rng, false);
    MpmState<dim>& s = scene.state;
    s.gravity.setZero();
    s.dt = 0.02;  // 20x the explicit limit dx / c of this material
    particles_to_grid(s.particles, s.buckets, s.kernel, s.transfer, s.grid);
    Vec<dim> before = Vec<dim>::Zero();  // grid.velocity holds the momentum m v after p2g
    for (const Vec<dim>& mv : s.grid.velocity) before += mv;
    const std::vector<Vec<dim>> predicted_momentum = s.grid.velocity;
    converged_step(scene);
    const Vec<dim> after = momentum(s.grid.mass, s.grid.velocity);
    // |sum_i g_i| <= sqrt(M) |g|_{M^-1} <= M tolerance rms(v^*): the converged residual bounds
    // the momentum error (v^* = v^n without gravity).
    double mass = 0.0, square = 0.0;
    for (std::size_t k = 0; k < s.grid.mass.size(); ++k)
      if (s.grid.mass[k] > 0.0) {
        mass += s.grid.mass[k];
      }
    for (std::size_t k = 0; k < s.grid.mass.size(); ++k)
      if (s.grid.mass[k] > 0.0) square += (predicted_momentum[k] / s.grid.mass[k]).squaredNorm() * s.grid.mass[k];
    CHECK((after - before).norm() <= 2e-10 * mass * std::sqrt(square / mass));
  }
}

TEST_CASE_TEMPLATE("implicit step with particle domains: Newton conserves the momentum of nodes and enriched corners",
                   Dim, std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  for (const std::string& model : constitutive::elastic_model_names()) {
    INFO(model, " in ", dim, "D");
    std::mt19937 rng(2019);
    solid::SolidScene<dim> scene = domain_scene<dim>(model, rng, false, false);  // no walls
    MpmState<dim>& s = scene.state;
    domains::ParticleDomains<dim>& d = *s.domains;
    REQUIRE(d.enriched_particles > 0);
    s.gravity.setZero();
    s.dt = 0.02;
    // Momentum and mass-weighted square speed of the unknowns before the step (the grid holds
    // m v after the transfer).
    Vec<dim> before = Vec<dim>::Zero();
    double mass = 0.0, square = 0.0;
    const auto add = [&](double m, const Vec<dim>& p) {
      if (m <= 0.0) return;
      before += p;
      mass += m;
      square += p.squaredNorm() / m;
    };
    for (std::size_t k = 0; k < s.grid.node_storage(); ++k) add(s.grid.mass[k], s.grid.velocity[k]);
    for (std::size_t c = 0; c < d.corner_count(); ++c)
      if (d.enriched[c]) add(d.mass[c], d.momentum[c]);
    converged_step(scene);
    // The enriched corners now hold their new velocities.
    Vec<dim> after = momentum(s.grid.mass, s.grid.velocity);
    for (std::size_t c = 0; c < d.corner_count(); ++c)
      if (d.enriched[c]) after += d.mass[c] * d.momentum[c];
    CHECK((after - before).norm() <= 2e-10 * mass * std::sqrt(square / mass));
    // Without the corners' share the balance fails: they carry momentum of their own.
    CHECK((after - momentum(s.grid.mass, s.grid.velocity)).norm() > 1e-3 * before.norm());
  }
}

TEST_CASE("implicit step: a stiff block rests on a sticky floor at a step 100x the explicit limit") {
  solid::SolidScene<2> scene = solid::load_solid_scene<2>(
      Config::parse(scene_yaml<2>("fixed_corotated", 1e10, true), "<string>", {"walls.contact=sticky"}));
  MpmState<2>& s = scene.state;
  const double explicit_dt = 0.5 * s.grid.dx() / scene.materials[0].wave_speed();
  s.dt = 100 * explicit_dt;
  const std::vector<Vec<2>> x0 = s.particles.x;
  Pipeline<MpmState<2>> pipeline = solid::make_solid_pipeline(scene);
  for (int n = 0; n < 50; ++n) {
    s.dt_limit = s.dt;  // the time-step stage keeps it (particles at rest impose nothing)
    pipeline.step(s);
    s.time += s.dt;
  }
  // A 1e10 Pa block under gravity compresses by rho g h / E ~ 1e-7 m: it must not move.
  double drift = 0.0;
  for (std::size_t p = 0; p < x0.size(); ++p) drift = std::max(drift, (s.particles.x[p] - x0[p]).norm());
  CHECK(drift < 1e-4 * s.grid.dx());
  for (const Vec<2>& v : s.particles.v) CHECK(v.allFinite());
}

TEST_CASE("implicit solver: bad input names the key") {
  const std::string yaml = scene_yaml<2>("neo_hookean", 1e5, true);
  const auto error = [&](const std::vector<std::string>& overrides) {
    try {
      solid::load_solid_scene<2>(Config::parse(yaml, "scene.yaml", overrides));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error({"implicit.tolerance=0"}).find("tolerance") != std::string::npos);
  CHECK(error({"implicit.tolerance=-1"}).find("expected a number > 0") != std::string::npos);
  CHECK(error({"implicit.max_newton_iterations=0"}).find("max_newton_iterations") != std::string::npos);
  CHECK(error({"implicit.max_linear_iterations=0"}).find("max_linear_iterations") != std::string::npos);
  CHECK(error({"implicit.linear_tolerance=1"}).find("linear_tolerance") != std::string::npos);
  CHECK(error({"implicit.on_failure=ignore"}).find("on_failure") != std::string::npos);
  CHECK(error({"solver=explicit", "implicit.tolerance=1e-6"}).find("solver: implicit") != std::string::npos);
  CHECK(error({"adaptive={levels: 2}"}).find("uniform grid") != std::string::npos);
  CHECK(error({}).empty());
}
