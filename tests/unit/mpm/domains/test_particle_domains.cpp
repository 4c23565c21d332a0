// Particle domains (mpm/domains/particle_domains.h, stages domains_to_grid / domains_from_grid):
// shared corners and F from the corners; the two-step transfer conserves mass and momentum,
// reproduces an affine velocity field and its deformation exactly; the grid forces are the
// negative gradient of the elastic energy with respect to the node positions (central
// differences); a free body keeps its momentum over many steps; bad input names the key.
#include <doctest/doctest.h>

#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/core/kernels.h>
#include <mpm/math/svd.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>
#include <mpm/solid/stages/domain_transfer.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

using namespace mpm;

namespace {

template <int dim>
std::string scene_yaml(const std::string& stretch = "") {
  const std::string lo = dim == 2 ? "[0, 0]" : "[0, 0, 0]", hi = dim == 2 ? "[1, 1]" : "[1, 1, 1]";
  const std::string blo = dim == 2 ? "[0.3, 0.4]" : "[0.3, 0.4, 0.4]",
                    bhi = dim == 2 ? "[0.6, 0.5]" : "[0.5, 0.5, 0.5]";
  const std::string g = dim == 2 ? "[0, 0]" : "[0, 0, 0]";
  return "dim: " + std::to_string(dim) + "\ndomain: {lo: " + lo + ", hi: " + hi + "}\ngrid: {dx: 0.05}\n" +
         "time: {end: 0.1}\ngravity: " + g + "\nwalls: {contact: separate}\ntransfer: {scheme: flip}\n" +
         "particle_domains: true\n" +
         "materials: [{name: m, density: 1000, youngs_modulus: 1e5, poisson_ratio: 0.3, elasticity: neo_hookean}]\n" +
         "bodies: [{shape: box, lo: " + blo + ", hi: " + bhi + ", material: m" + stretch + "}]\n";
}

double uniform(std::mt19937& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

template <int dim>
double total_elastic_energy(const solid::SolidScene<dim>& scene, const domains::ParticleDomains<dim>& d) {
  double e = 0.0;
  for (std::size_t p = 0; p < scene.state.particles.size(); ++p)
    e += scene.state.particles.volume0[p] * scene.materials[0].energy(d.deformation(p));
  return e;
}

//! w_i(x) of the quadratic B-spline for node `node`.
template <int dim>
double node_weight(const SparseGrid<dim>& grid, const IVec<dim>& node, const Vec<dim>& x) {
  double w = 1.0;
  for (int a = 0; a < dim; ++a) {
    int base;
    double wa[3], dwa[3];
    QuadraticBSpline{}((x[a] - grid.origin()[a]) / grid.dx(), base, wa, dwa);
    const int k = node[a] - base;
    w *= (k >= 0 && k < 3) ? wa[k] : 0.0;
  }
  return w;
}

}  // namespace

TEST_CASE_TEMPLATE("particle domains: corners are shared and F follows them", Dim, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  const std::string stretch = dim == 2 ? ", stretch: [1.5, -0.5]" : ", stretch: [1.5, -0.5, 0.2]";
  const solid::SolidScene<dim> scene = solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>(stretch)));
  const domains::ParticleDomains<dim>& d = *scene.state.domains;
  const Particles<dim>& P = scene.state.particles;
  // A box of n_a particles per axis has prod (n_a + 1) corners.
  Vec<dim> lo = P.x[0], hi = P.x[0];
  for (const Vec<dim>& x : P.x) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  const double h = std::pow(P.volume0[0] * std::fabs(dim == 2 ? 1.5 * 0.5 : 1.5 * 0.5 * 0.2), 1.0 / dim);
  std::size_t corners = 1;
  for (int a = 0; a < dim; ++a) corners *= static_cast<std::size_t>(std::lround((hi[a] - lo[a]) / h)) + 2;
  CHECK(d.corner_count() == corners);
  CHECK(d.particle_count() == P.size());
  CHECK(d.sharing.size() == P.size() * d.corners);
  const std::vector<Mat<dim>>& F = solid::elastic_F(P);
  for (std::size_t p = 0; p < P.size(); ++p) {
    CHECK((d.deformation(p) - F[p]).norm() < 1e-13);  // F = diag(stretch) from the corners
    CHECK((d.centre(p) - P.x[p]).norm() < 1e-14);
  }
}

TEST_CASE_TEMPLATE("particle domains: the surface is closed, outward and encloses the domains", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  for (const std::string shape : {"box", "sphere"}) {
    CAPTURE(shape);
    const std::string body = dim == 2 ? "{shape: sphere, center: [0.5, 0.5], radius: 0.17, material: m}"
                                      : "{shape: sphere, center: [0.5, 0.5, 0.5], radius: 0.17, material: m}";
    const solid::SolidScene<dim> scene = solid::load_solid_scene<dim>(
        Config::parse(scene_yaml<dim>(), "<string>",
                      shape == "box" ? std::vector<std::string>{} : std::vector<std::string>{"bodies=[" + body + "]"}));
    const domains::ParticleDomains<dim>& d = *scene.state.domains;
    const Particles<dim>& P = scene.state.particles;
    // The enclosed area (shoelace) or volume (divergence theorem, each quadrilateral as two
    // triangles) equals the domains' total: only with every face outward and none missing.
    double enclosed = 0.0;
    for (const auto& f : d.surface) {
      if constexpr (dim == 2)
        enclosed += 0.5 * (d.x[f[0]][0] * d.x[f[1]][1] - d.x[f[1]][0] * d.x[f[0]][1]);
      else
        enclosed += (d.x[f[0]].dot(d.x[f[1]].cross(d.x[f[2]])) + d.x[f[0]].dot(d.x[f[2]].cross(d.x[f[3]]))) / 6.0;
    }
    double volume = 0.0;
    for (const double v : P.volume0) volume += v;
    CHECK(enclosed == doctest::Approx(volume).epsilon(1e-12));
    if (shape == "box") {  // n_a particles per axis: 2 (n_x + n_y) edges, 2 (n_x n_y + ...) faces
      Vec<dim> lo = P.x[0], hi = P.x[0];
      for (const Vec<dim>& x : P.x) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
      const double h = std::pow(P.volume0[0], 1.0 / dim);
      const Vec<dim> n = ((hi - lo) / h).array().round() + 1.0;
      const double faces = dim == 2 ? 2 * (n[0] + n[1]) : 2 * (n[0] * n[1] + n[1] * n[2] + n[2] * n[0]);
      CHECK(d.surface.size() == static_cast<std::size_t>(faces));
    }
  }
}

TEST_CASE_TEMPLATE("particle domains: the two-step transfer conserves and reproduces affine motion", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(7);
  solid::SolidScene<dim> scene =
      solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>(), "<string>", {"transfer.flip_ratio=0"}));
  MpmState<dim>& s = scene.state;
  Particles<dim>& P = s.particles;
  for (Vec<dim>& v : P.v) v = Vec<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); });
  s.dt = 1e-3;
  stages::DomainsToGrid<dim> to_grid(scene.materials);
  to_grid.run(s);
  // Mass and momentum reach the grid whole; at rest (F = I) the forces vanish.
  double m_grid = 0.0;
  Vec<dim> p_grid = Vec<dim>::Zero(), p_particles = Vec<dim>::Zero(), f_sum = Vec<dim>::Zero();
  for (std::size_t k = 0; k < s.grid.node_storage(); ++k) {
    m_grid += s.grid.mass[k];
    p_grid += s.grid.velocity[k];
    f_sum += s.grid.force[k];
  }
  for (std::size_t p = 0; p < P.size(); ++p) p_particles += P.mass[p] * P.v[p];
  CHECK(std::fabs(m_grid - P.total_mass()) < 1e-12 * P.total_mass());
  CHECK((p_grid - p_particles).norm() < 1e-12 * P.total_mass());
  CHECK(f_sum.norm() < 1e-9);
  // An affine grid velocity v = b + A x: PIC gives v_p = b + A x_p and F = (I + dt A) F exactly.
  const Vec<dim> b = Vec<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); });
  const Mat<dim> A = Mat<dim>::NullaryExpr([&] { return uniform(rng, -2.0, 2.0); });
  for (std::size_t k = 0; k < s.grid.node_storage(); ++k) s.grid.velocity[k] = b + A * s.grid.node_position(k);
  s.grid.velocity_old = s.grid.velocity;
  std::vector<Vec<dim>> x0 = P.x;
  const std::vector<Mat<dim>> F0 = solid::elastic_F(P);
  stages::DomainsFromGrid<dim>(scene.colliders, false, false).run(s);
  const std::vector<Mat<dim>>& F = solid::elastic_F(P);
  double v_error = 0.0, x_error = 0.0, F_error = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    v_error = std::max(v_error, (P.v[p] - (b + A * x0[p])).norm());
    x_error = std::max(x_error, (P.x[p] - (x0[p] + s.dt * (b + A * x0[p]))).norm());
    F_error = std::max(F_error, (F[p] - (Mat<dim>::Identity() + s.dt * A) * F0[p]).norm());
  }
  CHECK(v_error < 1e-12);
  CHECK(x_error < 1e-14);
  CHECK(F_error < 1e-12);
}

TEST_CASE_TEMPLATE("particle domains: grid forces are minus the energy gradient", Dim, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(11);
  // Seeded stretched with one axis inverted: the reference gradients carry the sign.
  solid::SolidScene<dim> scene = solid::load_solid_scene<dim>(
      Config::parse(scene_yaml<dim>(dim == 2 ? ", stretch: [1.2, -0.8]" : ", stretch: [1.2, -0.8, 0.9]")));
  MpmState<dim>& s = scene.state;
  domains::ParticleDomains<dim>& d = *s.domains;
  for (Vec<dim>& x : d.x) x += Vec<dim>::NullaryExpr([&] { return uniform(rng, -0.004, 0.004); });
  std::vector<Mat<dim>>& F = solid::elastic_F(s.particles);
  for (std::size_t p = 0; p < F.size(); ++p) F[p] = d.deformation(p);
  stages::DomainsToGrid<dim>(scene.materials).run(s);
  // Moving node i by u moves each corner by w_i(x_alpha) u: E(u) of the new corners.
  const std::vector<Vec<dim>> corners = d.x;
  const double eps = 1e-6;
  double worst = 0.0, largest = 0.0;
  for (std::size_t k = 0; k < s.grid.node_storage(); k += 7) {
    if (s.grid.mass[k] <= 0.0) continue;
    const IVec<dim> node = s.grid.node_coord(k);
    for (int a = 0; a < dim; ++a) {
      double e[2];
      for (int side = 0; side < 2; ++side) {
        for (std::size_t c = 0; c < corners.size(); ++c)
          d.x[c] = corners[c] + (side ? eps : -eps) * node_weight(s.grid, node, corners[c]) * Vec<dim>::Unit(a);
        e[side] = total_elastic_energy(scene, d);
      }
      const double f_difference = -(e[1] - e[0]) / (2 * eps);
      worst = std::max(worst, std::fabs(f_difference - s.grid.force[k][a]));
      largest = std::max(largest, std::fabs(s.grid.force[k][a]));
    }
  }
  d.x = corners;
  CHECK(largest > 1.0);  // the perturbed body is stressed
  CHECK(worst < 1e-6 * largest);
}

TEST_CASE_TEMPLATE("particle domains: a free spinning, deforming body keeps its momentum", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(3);
  solid::SolidScene<dim> scene = solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>()));
  MpmState<dim>& s = scene.state;
  Particles<dim>& P = s.particles;
  for (Vec<dim>& v : P.v) v = Vec<dim>::NullaryExpr([&] { return uniform(rng, -0.3, 0.3); });
  Vec<dim> p0 = Vec<dim>::Zero();
  for (std::size_t p = 0; p < P.size(); ++p) p0 += P.mass[p] * P.v[p];
  Pipeline<MpmState<dim>> pipeline = solid::make_solid_pipeline(scene);
  double scale = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) scale += P.mass[p] * P.v[p].norm();
  for (int n = 0; n < 40; ++n) {
    s.dt_limit = 1e-3;
    pipeline.step(s);
    s.time += s.dt;
  }
  Vec<dim> p1 = Vec<dim>::Zero();
  for (std::size_t p = 0; p < P.size(); ++p) p1 += P.mass[p] * P.v[p];
  CHECK((p1 - p0).norm() < 1e-12 * scale);
  for (std::size_t p = 0; p < P.size(); ++p) CHECK((s.domains->centre(p) - P.x[p]).norm() == 0.0);
}

TEST_CASE_TEMPLATE("particle domains: the enrichment metric is sigma_min / sigma_max", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(5);
  const Mat<dim> R = math::polar(Mat<dim>(Mat<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); }))).R;
  // Closed form: to about 1e-8 where eigenvalues of F^T F coincide (the repeated 2 below).
  CHECK(domains::enrichment_metric<dim>(R) == doctest::Approx(1.0).epsilon(1e-12));
  Vec<dim> stretch = Vec<dim>::Constant(2.0);
  stretch[0] = 0.5;
  CHECK(domains::enrichment_metric<dim>(R * stretch.asDiagonal() * R.transpose()) ==
        doctest::Approx(0.25).epsilon(1e-7));
  stretch[0] = -1.0;  // inverted: the metric sees |sigma|
  CHECK(domains::enrichment_metric<dim>(R * stretch.asDiagonal()) == doctest::Approx(0.5).epsilon(1e-7));
  CHECK(domains::enrichment_metric<dim>(Mat<dim>::Zero()) == 0.0);
  // A thin domain keeps its relative accuracy: sigma = (1, 1e-6(, 1)).
  stretch.setOnes();
  stretch[1] = 1e-6;
  CHECK(domains::enrichment_metric<dim>(R * stretch.asDiagonal()) == doctest::Approx(1e-6).epsilon(1e-6));
  // Against the SVD on random matrices.
  double worst = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const Mat<dim> F = Mat<dim>::Identity() + Mat<dim>::NullaryExpr([&] { return uniform(rng, -0.7, 0.7); });
    const Vec<dim> sigma = math::svd(F).sigma;
    worst = std::max(worst, std::fabs(domains::enrichment_metric<dim>(F) - std::fabs(sigma[dim - 1]) / sigma[0]));
  }
  CHECK(worst < 1e-9);
}

TEST_CASE_TEMPLATE("particle domains: enriched corners are degrees of freedom of their own", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(13);
  const auto step = [](solid::SolidScene<dim>& scene, Pipeline<MpmState<dim>>& pipeline, int steps) {
    for (int n = 0; n < steps; ++n) {
      scene.state.dt_limit = 1e-3;
      pipeline.step(scene.state);
      scene.state.time += scene.state.dt;
    }
  };
  const auto momentum = [](const Particles<dim>& P) {
    Vec<dim> sum = Vec<dim>::Zero();
    for (std::size_t p = 0; p < P.size(); ++p) sum += P.mass[p] * P.v[p];
    return sum;
  };
  SUBCASE("no particle enriched: the run is the run without enrichment, bit for bit") {
    solid::SolidScene<dim> a = solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>()));
    solid::SolidScene<dim> b =
        solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>(), "<string>", {"domain_enrichment=1e-9"}));
    for (solid::SolidScene<dim>* scene : {&a, &b}) {
      std::mt19937 same(3);
      for (Vec<dim>& v : scene->state.particles.v) v = Vec<dim>::NullaryExpr([&] { return uniform(same, -1.0, 1.0); });
    }
    Pipeline<MpmState<dim>> pa = solid::make_solid_pipeline(a), pb = solid::make_solid_pipeline(b);
    step(a, pa, 30);
    step(b, pb, 30);
    CHECK(b.state.domains->enriched_particles == 0);
    CHECK(b.state.domains->enriched.size() == b.state.domains->corner_count());
    CHECK(a.state.particles.x == b.state.particles.x);
    CHECK(a.state.particles.v == b.state.particles.v);
  }
  SUBCASE("a stretched body is all enriched: nothing reaches the grid, its thinnest domain bounds the step") {
    // F = diag(1.5, 0.5[, 1]): K = 1/3 <= 0.6. A domain is one spacing thick across every
    // axis, half a cell: the mesh's bound, not the grid's, sets dt.
    solid::SolidScene<dim> scene = solid::load_solid_scene<dim>(
        Config::parse(scene_yaml<dim>(dim == 2 ? ", stretch: [1.5, 0.5]" : ", stretch: [1.5, 0.5, 1]"), "<string>",
                      {"domain_enrichment=0.6"}));
    MpmState<dim>& s = scene.state;
    Pipeline<MpmState<dim>> pipeline = solid::make_solid_pipeline(scene);
    s.dt_limit = 1.0;  // no frame end: the stable step alone
    pipeline.step(s);
    const domains::ParticleDomains<dim>& d = *s.domains;
    CHECK(d.enriched_particles == s.particles.size());
    const double spacing = (d.x[d.corner_of[0][1]] - d.x[d.corner_of[0][0]]).norm();  // one step on
    CHECK(d.enriched_length == doctest::Approx(spacing).epsilon(0.01));
    double grid_mass = 0.0;
    for (const double m : s.grid.mass) grid_mass += m;
    CHECK(grid_mass == 0.0);
    // The step the time-step stage chose is the mesh's Courant bound (at rest: no speed limit).
    CHECK(s.dt == doctest::Approx(scene.settings.wave_cfl * d.enriched_length / scene.solver->wave_speed()));
    CHECK(s.dt < 0.6 * scene.settings.wave_cfl * scene.settings.dx / scene.solver->wave_speed());
  }
  SUBCASE("transitional particles: momentum is kept and the energy stays bounded") {
    // Corners jostled so that some particles are enriched (K <= 0.9), some transitional, some not.
    solid::SolidScene<dim> scene =
        solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>(), "<string>", {"domain_enrichment=0.9"}));
    MpmState<dim>& s = scene.state;
    domains::ParticleDomains<dim>& d = *s.domains;
    const double spacing = (d.x[d.corner_of[0][1]] - d.x[d.corner_of[0][0]]).norm();
    for (Vec<dim>& x : d.x) x += Vec<dim>::NullaryExpr([&] { return uniform(rng, -0.06, 0.06) * spacing; });
    std::vector<Mat<dim>>& F = solid::elastic_F(s.particles);
    for (std::size_t p = 0; p < F.size(); ++p) {
      F[p] = d.deformation(p);
      s.particles.x[p] = d.centre(p);
    }
    for (Vec<dim>& v : s.particles.v) v = Vec<dim>::NullaryExpr([&] { return uniform(rng, -0.2, 0.2); });
    const Vec<dim> p0 = momentum(s.particles);
    double scale = 0.0;
    for (std::size_t p = 0; p < F.size(); ++p) scale += s.particles.mass[p] * s.particles.v[p].norm();
    const auto energy = [&] {
      double e = total_elastic_energy(scene, d);
      for (std::size_t p = 0; p < F.size(); ++p) e += 0.5 * s.particles.mass[p] * s.particles.v[p].squaredNorm();
      return e;
    };
    const double e0 = energy();
    Pipeline<MpmState<dim>> pipeline = solid::make_solid_pipeline(scene);
    step(scene, pipeline, 1);
    CHECK(d.enriched_particles > 0);
    CHECK(d.enriched_particles < s.particles.size());
    step(scene, pipeline, 59);
    CHECK((momentum(s.particles) - p0).norm() < 1e-12 * scale);
    CHECK(energy() < 1.05 * e0);  // PIC/FLIP dissipates; a wrong corner force would blow up
    for (std::size_t p = 0; p < F.size(); ++p) CHECK((d.centre(p) - s.particles.x[p]).norm() == 0.0);
  }
}

TEST_CASE_TEMPLATE("particle domains: a flat enriched domain stops an explicit step, not an implicit one", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  solid::SolidScene<dim> scene =
      solid::load_solid_scene<dim>(Config::parse(scene_yaml<dim>(), "<string>", {"domain_enrichment=0.6"}));
  domains::ParticleDomains<dim>& d = *scene.state.domains;
  std::vector<Mat<dim>> F(d.particle_count(), Mat<dim>::Identity());
  F[7](1, 1) = 1e-8;  // particle 7 crushed to 1e-8 of its height
  try {
    domains::mark_enrichment(d, F);
    FAIL("no error for a flat enriched domain");
  } catch (const NumericalError& e) {
    CHECK(std::string(e.what()).find("particle 7 is flat") != std::string::npos);
  }
  domains::mark_enrichment(d, F, false);  // an implicit step: no Courant bound, no error
  CHECK(d.enriched_particles == 1);
  CHECK(std::isinf(d.enriched_length));
  F[7](1, 1) = 1e-3;  // thin but not flat: the explicit bound is its thickness
  domains::mark_enrichment(d, F);
  CHECK(d.enriched_length == doctest::Approx(1e-3 / d.inverse_side[7][1]).epsilon(1e-9));
}

TEST_CASE("particle domains: enriched corners obey the walls") {
  // A stretched block thrown at the floor, enriched wherever it deforms: the enriched corners
  // that reach the floor stop at its wall layer (the colliders act on them as on nodes).
  solid::SolidScene<2> scene = solid::load_solid_scene<2>(
      Config::parse(scene_yaml<2>(", stretch: [1.5, 0.5], velocity: [0, -6]"), "<string>", {"domain_enrichment=0.98"}));
  MpmState<2>& s = scene.state;
  const domains::ParticleDomains<2>& d = *s.domains;
  Pipeline<MpmState<2>> pipeline = solid::make_solid_pipeline(scene);
  const double floor = scene.settings.domain_lo[1] + scene.colliders.walls()->thickness();
  double lowest = 1.0, travel = 0.0;
  for (int n = 0; n < 2000 && s.time < 0.15; ++n) {
    s.dt_limit = 1e-3;
    pipeline.step(s);
    s.time += s.dt;
    for (std::size_t c = 0; c < d.corner_count(); ++c)
      if (d.enriched[c]) lowest = std::min(lowest, d.x[c][1]), travel = std::max(travel, s.dt * d.momentum[c].norm());
  }
  CHECK(s.time >= 0.15);
  CHECK(lowest > floor - 1.5 * travel);             // within a step's travel of the layer
  CHECK(lowest < floor + 0.1 * scene.settings.dx);  // enriched corners did reach the floor
}

namespace {
//! An elastic box and a snowball (snow plasticity) thrown at it and at the floor; `domains`:
//! the box's key (the snowball is a material point body either way).
template <int dim>
std::string mixed_scene_yaml(const std::string& particle_domains, const std::string& box_domains) {
  const std::string lo = dim == 2 ? "[0, 0]" : "[0, 0, 0]", hi = dim == 2 ? "[1, 1]" : "[1, 1, 1]";
  const std::string blo = dim == 2 ? "[0.5, 0.1]" : "[0.5, 0.1, 0.4]",
                    bhi = dim == 2 ? "[0.7, 0.4]" : "[0.65, 0.3, 0.55]";
  const std::string centre = dim == 2 ? "[0.3, 0.25]" : "[0.3, 0.2, 0.47]";
  const std::string v = dim == 2 ? "[4, -3]" : "[4, -3, 0.5]";
  const std::string g = dim == 2 ? "[0, -9.81]" : "[0, -9.81, 0]";
  return "dim: " + std::to_string(dim) + "\ndomain: {lo: " + lo + ", hi: " + hi + "}\ngrid: {dx: 0.05}\n" +
         "time: {end: 0.1}\ngravity: " + g + "\nwalls: {contact: separate}\n" +
         "transfer: {scheme: flip, flip_ratio: 0.9}\nparticle_domains: " + particle_domains + "\n" +
         "materials: [{name: m, density: 1000, youngs_modulus: 1e5, poisson_ratio: 0.3, elasticity: neo_hookean},\n" +
         "  {name: snow, density: 400, youngs_modulus: 1.4e5, poisson_ratio: 0.2, elasticity: fixed_corotated,\n" +
         "   plasticity: {model: snow, critical_compression: 2.5e-2, critical_stretch: 7.5e-3, hardening: 10}}]\n" +
         "bodies: [{shape: box, lo: " + blo + ", hi: " + bhi + ", material: m" + box_domains + "},\n" +
         "  {shape: sphere, center: " + centre + ", radius: 0.1, material: snow, velocity: " + v + "}]\n";
}

template <int dim>
void run_steps(solid::SolidScene<dim>& scene, int steps) {
  Pipeline<MpmState<dim>> pipeline = solid::make_solid_pipeline(scene);
  for (int n = 0; n < steps; ++n) {
    scene.state.dt_limit = 5e-4;
    pipeline.step(scene.state);
    scene.state.time += scene.state.dt;
  }
}
}  // namespace

TEST_CASE_TEMPLATE("particle domains: material points among them take the standard step", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  // Every body a material point (domains: false) in a scene with particle_domains: the
  // standard pipeline's FLIP step, stress scatter, F update and snow return map, to round-off.
  constexpr int dim = Dim::value;
  solid::SolidScene<dim> points =
      solid::load_solid_scene<dim>(Config::parse(mixed_scene_yaml<dim>("true", ", domains: false")));
  solid::SolidScene<dim> standard = solid::load_solid_scene<dim>(Config::parse(mixed_scene_yaml<dim>("false", "")));
  REQUIRE(points.state.domains->point_count == points.state.particles.size());
  // A tag follows each particle of the standard run through its sorts.
  auto& tag = standard.state.particles.template add_channel<double>("tag", 0.0, ChannelUse{});
  for (std::size_t p = 0; p < tag.size(); ++p) tag[p] = static_cast<double>(p);
  run_steps(points, 120);
  run_steps(standard, 120);
  const Particles<dim>&A = points.state.particles, &B = standard.state.particles;
  REQUIRE(A.size() == B.size());
  CHECK(points.state.time == doctest::Approx(standard.state.time).epsilon(1e-14));
  const auto& FA = solid::elastic_F(A);
  const auto& FB = solid::elastic_F(B);
  const auto& plastic = solid::plastic_state(A);
  double dx = 0.0, dv = 0.0, dF = 0.0, vmax = 0.0, hardened = 0.0;
  for (std::size_t q = 0; q < B.size(); ++q) {
    const auto p = static_cast<std::size_t>(B.template channel<double>("tag")[q]);
    dx = std::max(dx, (A.x[p] - B.x[q]).norm());
    dv = std::max(dv, (A.v[p] - B.v[q]).norm());
    dF = std::max(dF, (FA[p] - FB[q]).norm());
    vmax = std::max(vmax, B.v[q].norm());
    hardened = std::max(hardened, std::fabs(plastic[p]));
  }
  CHECK(hardened > 1e-3);  // the snow yielded, so the return map is part of the comparison
  CHECK(dx < 1e-11);
  CHECK(dv < 1e-9 * vmax);
  CHECK(dF < 1e-9);
}

TEST_CASE_TEMPLATE("particle domains: a body with domains and material points conserve momentum as they meet", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  // No gravity, and walls only on the boundary nodes, which the bodies' stencils never reach.
  std::vector<std::string> no_gravity{dim == 2 ? "gravity=[0, 0]" : "gravity=[0, 0, 0]", "walls.thickness=0.01"};
  solid::SolidScene<dim> scene =
      solid::load_solid_scene<dim>(Config::parse(mixed_scene_yaml<dim>("true", ""), "scene.yaml", no_gravity));
  const domains::ParticleDomains<dim>& d = *scene.state.domains;
  const Particles<dim>& P = scene.state.particles;
  REQUIRE(d.point_count > 0);
  REQUIRE(d.point_count < P.size());
  // Aim the ball at the box instead of the floor.
  for (std::size_t p = 0; p < P.size(); ++p)
    if (d.is_point(p)) scene.state.particles.v[p][1] = 0.0;
  const auto momentum = [&] {
    Vec<dim> m = Vec<dim>::Zero();
    for (std::size_t p = 0; p < P.size(); ++p) m += P.mass[p] * P.v[p];
    return m;
  };
  const Vec<dim> p0 = momentum();
  double scale = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) scale += P.mass[p] * P.v[p].norm();
  run_steps(scene, 80);
  double box_speed = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p)
    if (!d.is_point(p)) box_speed = std::max(box_speed, P.v[p].norm());
  CHECK(box_speed > 0.1);  // the ball has hit the box
  CHECK((momentum() - p0).norm() < 1e-12 * scale);
}

TEST_CASE("particle domains: bad input names the key") {
  const std::string yaml = scene_yaml<2>();
  const auto error = [&](const std::vector<std::string>& overrides) {
    try {
      solid::load_solid_scene<2>(Config::parse(yaml, "scene.yaml", overrides));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error({}).empty());
  CHECK(error({"transfer.scheme=apic"}).find("transfer.scheme: flip") != std::string::npos);
  CHECK(error({"solver=implicit"}).empty());
  CHECK(error({"solver=grains"}).find("solver: explicit or implicit") != std::string::npos);
  CHECK(error({"adaptive={levels: 2}"}).find("uniform grid") != std::string::npos);
  CHECK(error({"materials.0.elasticity=hencky_stvk", "materials.0.plasticity={model: von_mises, yield_stress: 1e4}",
               "bodies.0.domains=true"})
            .find("is plastic") != std::string::npos);
  CHECK(error({"particle_domains=maybe"}).find("particle_domains") != std::string::npos);
  CHECK(error({"domain_enrichment=1"}).find("domain_enrichment") != std::string::npos);
  CHECK(error({"domain_enrichment=1"}).find("(0, 1)") != std::string::npos);
  CHECK(error({"domain_enrichment=-0.1"}).find("domain_enrichment") != std::string::npos);
  CHECK(error({"particle_domains=false", "domain_enrichment=0.6"}).find("needs particle_domains: true") !=
        std::string::npos);
  CHECK(error({"bodies.0.jitter=0.3"}).find("jitter must be 0") != std::string::npos);
  // The enriched surfaces' self-contact: a fraction in [0, 1), with enrichment, explicit only.
  CHECK(error({"domain_enrichment=0.6", "domain_contact=0"}).empty());
  CHECK(error({"domain_enrichment=0.6", "domain_contact=1"}).find("domain_contact") != std::string::npos);
  CHECK(error({"domain_enrichment=0.6", "domain_contact=-0.1"}).find("[0, 1)") != std::string::npos);
  CHECK(error({"domain_contact=0.2"}).find("needs domain_enrichment") != std::string::npos);
  CHECK(error({"domain_enrichment=0.6", "solver=implicit"}).empty());
  CHECK(error({"domain_enrichment=0.6", "domain_contact=0.2", "solver=implicit"}).find("explicit step only") !=
        std::string::npos);
  // Material points: any body may be one; a plastic body must be; an implicit step takes none.
  CHECK(error({"bodies.0.domains=false"}).empty());
  CHECK(error({"bodies.0.domains=false", "solver=implicit"}).find("domains on every body") != std::string::npos);
  CHECK(error({"particle_domains=false", "bodies.0.domains=false"}).find("bodies.0.domains") != std::string::npos);
  CHECK(
      error({"materials.0.elasticity=fixed_corotated", "materials.0.plasticity={model: snow}", "bodies.0.domains=true"})
          .find("set domains: false") != std::string::npos);
  CHECK(error({"materials.0.elasticity=fixed_corotated", "materials.0.plasticity={model: snow}"}).empty());
  CHECK(error({"periodic=[true, false]", "walls={contact: separate, x_min: open, x_max: open}"})
            .find("no periodic axis") != std::string::npos);
}

TEST_CASE_TEMPLATE("particle domains: an embedded mesh follows the corners' affine map, outside the particles too", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(5);
  // A box of 4 x 3 (x 5) particles of spacing h, and mesh vertices anywhere within 1.5 spacings
  // of its domains: inside the particles' cells and beyond them (nearest domain, extrapolated).
  const double h = 0.1;
  const Vec<dim> lo = Vec<dim>::Constant(0.3);
  IVec<dim> n;
  for (int a = 0; a < dim; ++a) n[a] = 3 + (a == 0) + 2 * (a == 2);
  std::vector<Vec<dim>> positions;
  for (int k = 0; k < n.prod(); ++k) {
    Vec<dim> x;
    for (int a = 0, m = k; a < dim; m /= n[a], ++a) x[a] = lo[a] + h * (m % n[a]);
    positions.push_back(x);
  }
  std::vector<Vec<dim>> vertices(200);
  for (Vec<dim>& v : vertices)
    for (int a = 0; a < dim; ++a) v[a] = uniform(rng, lo[a] - 2.0 * h, lo[a] + (n[a] + 1.0) * h);
  const std::vector<std::array<std::uint32_t, 3>> triangles{{0, 1, 2}, {2, 3, 199}};
  domains::ParticleDomains<dim> d;
  domains::add_body<dim>(d, 0, positions, h, Vec<dim>::Ones());
  domains::embed_mesh<dim>(d, 0, positions, h, vertices, triangles);
  domains::index_sharing(d);
  REQUIRE(d.embedded_domain.size() == vertices.size());
  CHECK(d.embedded_triangles == triangles);
  // At seeding the embedded vertices are the mesh's; after x -> A x + b of every corner they are
  // A X + b (the trilinear map of a domain reproduces affine motion, extended beyond it too).
  const Mat<dim> A = Mat<dim>::Identity() + 0.4 * Mat<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); });
  const Vec<dim> b = Vec<dim>::NullaryExpr([&] { return uniform(rng, -1.0, 1.0); });
  double seeded = 0.0, moved = 0.0, inside = 0.0;
  for (std::size_t v = 0; v < vertices.size(); ++v)
    seeded = std::max(seeded, (d.embedded_position(v) - vertices[v]).norm());
  for (Vec<dim>& x : d.x) x = A * x + b;
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    moved = std::max(moved, (d.embedded_position(v) - (A * vertices[v] + b)).norm());
    // Within the particles' cells a vertex lies in the cell that holds it: 0 <= xi <= 1.
    const Vec<dim> u = (vertices[v] - lo) / h;
    if ((u.array() > -0.5).all() && (u.array() < n.template cast<double>().array() - 0.5).all())
      inside = std::max(inside, std::max(-d.embedded_local[v].minCoeff(), d.embedded_local[v].maxCoeff() - 1.0));
  }
  CHECK(seeded < 1e-13);
  CHECK(moved < 1e-12);
  CHECK(inside <= 1e-12);
  // A vertex beyond two spacings of every particle, and a triangle naming a missing vertex.
  domains::ParticleDomains<dim> e;
  domains::add_body<dim>(e, 0, positions, h, Vec<dim>::Ones());
  CHECK_THROWS_WITH_AS(domains::embed_mesh<dim>(e, 0, positions, h, {lo - Vec<dim>::Constant(3.0 * h)}, {}),
                       doctest::Contains("mesh vertex 0"), Error);
  CHECK_THROWS_WITH_AS(domains::embed_mesh<dim>(e, 0, positions, h, {lo}, {{0, 0, 1}}),
                       doctest::Contains("vertex 1 of 1"), Error);
}

#ifdef MPM_WITH_OPENVDB
TEST_CASE("particle domains: a body seeded from a mesh carries that mesh, embedded") {
  // A closed octahedron of "radius" 0.2 m about (0.5, 0.5, 0.5), seeded through its level set.
  const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                     ("mpm_test_octahedron_" + std::to_string(std::random_device{}()) + ".obj");
  std::ofstream(file) << "v 0.7 0.5 0.5\nv 0.3 0.5 0.5\nv 0.5 0.7 0.5\nv 0.5 0.3 0.5\nv 0.5 0.5 0.7\nv 0.5 0.5 0.3\n"
                         "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  const std::string body = "[{shape: level_set, file: " + file.string() + ", voxel_size: 0.01, material: m}]";
  const solid::SolidScene<3> scene =
      solid::load_solid_scene<3>(Config::parse(scene_yaml<3>(), "<string>", {"bodies=" + body}));
  std::filesystem::remove(file);
  const domains::ParticleDomains<3>& d = *scene.state.domains;
  REQUIRE(d.embedded_domain.size() == 6);
  CHECK(d.embedded_triangles.size() == 8);
  CHECK((d.embedded_position(0) - Vec<3>(0.7, 0.5, 0.5)).norm() < 1e-12);
  CHECK((d.embedded_position(5) - Vec<3>(0.5, 0.5, 0.3)).norm() < 1e-12);
}
#endif
