// Self-contact of enriched particle domains (mpm/domains/surface_contact.h): the impulses
// conserve linear and angular momentum to round-off; after them no vertex-face pair within reach
// closes below min(gap, h) in the step (checked against a brute-force closest point over every
// pair); separating pairs, pairs without an enriched corner and scenes without enrichment are
// left alone, bit for bit.
#include <doctest/doctest.h>

#include <mpm/core/error.h>
#include <mpm/domains/surface_contact.h>

#include <Eigen/Geometry>

#include <array>
#include <limits>
#include <random>
#include <vector>

using namespace mpm;

namespace {

//! Lattice points of a box of n_a cells of spacing h from `lo` (the particles, at cell centres).
template <int dim>
std::vector<Vec<dim>> lattice(const Vec<dim>& lo, const IVec<dim>& n, double h) {
  std::vector<Vec<dim>> x;
  IVec<dim> i = IVec<dim>::Zero();
  while (true) {
    x.push_back(lo + h * (i.template cast<double>().array() + 0.5).matrix());
    int a = 0;
    for (; a < dim && ++i[a] == n[a]; ++a) i[a] = 0;
    if (a == dim) return x;
  }
}

//! Two bodies of spacing h: a slab below and a block above it, `gap` apart, every corner
//! enriched, random corner masses; the block moves down at `speed` plus a random spread.
template <int dim>
domains::ParticleDomains<dim> two_bodies(double h, double gap, double speed, std::mt19937& rng) {
  domains::ParticleDomains<dim> d;
  IVec<dim> slab = IVec<dim>::Constant(4), block = IVec<dim>::Constant(2);
  slab[dim - 1] = 1;
  const std::vector<Vec<dim>> below = lattice<dim>(Vec<dim>::Zero(), slab, h);
  Vec<dim> lo = Vec<dim>::Constant(0.7 * h);
  lo[dim - 1] = h + gap;
  const std::vector<Vec<dim>> above = lattice<dim>(lo, block, h);
  domains::add_body<dim>(d, 0, below, h, Vec<dim>::Ones());
  domains::add_body<dim>(d, below.size(), above, h, Vec<dim>::Ones());
  domains::index_sharing(d);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  d.enriched.assign(d.corner_count(), 1);
  d.mass.resize(d.corner_count());
  d.momentum.resize(d.corner_count());
  d.force.assign(d.corner_count(), Vec<dim>::Zero());
  for (std::size_t c = 0; c < d.corner_count(); ++c) {
    d.mass[c] = 1.0 + 0.5 * u(rng);
    d.momentum[c] = Vec<dim>::NullaryExpr([&] { return 0.2 * speed * u(rng); });
    if (d.x[c][dim - 1] > h + 0.5 * gap) d.momentum[c][dim - 1] -= speed;  // the block comes down
  }
  return d;
}

template <int dim>
Vec<dim> total_momentum(const domains::ParticleDomains<dim>& d) {
  Vec<dim> p = Vec<dim>::Zero();
  for (std::size_t c = 0; c < d.corner_count(); ++c) p += d.mass[c] * d.momentum[c];
  return p;
}

template <int dim>
Eigen::Vector3d angular_momentum(const domains::ParticleDomains<dim>& d) {
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (std::size_t c = 0; c < d.corner_count(); ++c) {
    Eigen::Vector3d x = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
    x.head<dim>() = d.x[c];
    v.head<dim>() = d.mass[c] * d.momentum[c];
    l += x.cross(v);
  }
  return l;
}

//! Barycentric weights over a face of the slab's top (z = top) of the point y of that plane,
//! as the contact splits the face: an edge in 2D, the triangles (0, 1, 2) and (0, 2, 3) in 3D;
//! empty when y is outside the face.
template <int dim>
std::vector<double> weights_on_top(const domains::ParticleDomains<dim>& d,
                                   const std::array<std::uint32_t, (1 << dim) / 2>& face, const Vec<dim>& y) {
  std::vector<double> b(face.size(), 0.0);
  if constexpr (dim == 2) {
    const double t = (y[0] - d.x[face[0]][0]) / (d.x[face[1]][0] - d.x[face[0]][0]);
    if (t <= 0.0 || t >= 1.0) return {};
    b[0] = 1.0 - t, b[1] = t;
  } else {
    for (const std::array<int, 3> tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
      Eigen::Matrix2d A;
      const Eigen::Vector2d o = d.x[face[tri[0]]].template head<2>();
      A.col(0) = d.x[face[tri[1]]].template head<2>() - o;
      A.col(1) = d.x[face[tri[2]]].template head<2>() - o;
      const Eigen::Vector2d w = A.inverse() * (y.template head<2>() - o);
      if (w.minCoeff() < 0.0 || w.sum() > 1.0) continue;
      b[tri[0]] = 1.0 - w.sum(), b[tri[1]] = w[0], b[tri[2]] = w[1];
      return b;
    }
    return {};
  }
  return b;
}

//! The smallest g + dt v_n - min(g, h) over every pair of a block vertex and a face of the
//! slab's top (z = top) that the vertex lies over: there the closest point is the vertex's
//! projection, the normal is e_z and the gap is the height above the top, computed here
//! without the contact's closest-point routine.
template <int dim>
double worst_closing(const domains::ParticleDomains<dim>& d, double h, double dt, double top) {
  double worst = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < d.corner_count(); ++c) {
    if (d.x[c][dim - 1] < top + 1e-12) continue;  // a vertex of the block
    for (const auto& face : d.surface) {
      bool on_top = true;
      for (const std::uint32_t k : face) on_top = on_top && std::abs(d.x[k][dim - 1] - top) < 1e-12;
      const std::vector<double> b = on_top ? weights_on_top(d, face, d.x[c]) : std::vector<double>{};
      if (b.empty()) continue;
      const double gap = d.x[c][dim - 1] - top;
      double v_n = d.momentum[c][dim - 1];
      for (std::size_t k = 0; k < face.size(); ++k) v_n -= b[k] * d.momentum[face[k]][dim - 1];
      worst = std::min(worst, gap + dt * v_n - std::min(gap, h));
    }
  }
  return worst;
}

}  // namespace

TEST_CASE_TEMPLATE("surface contact: momentum kept, no pair closes below the thickness", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(7);
  const double h = 0.01, thickness = 0.1 * h, dt = 1e-3;
  for (const double gap : {0.05 * h, 0.3 * h}) {  // inside the thickness, and closing from outside it
    CAPTURE(gap);
    domains::ParticleDomains<dim> d = two_bodies<dim>(h, gap, 2.0 * gap / dt, rng);
    const Vec<dim> p0 = total_momentum(d);
    const Eigen::Vector3d l0 = angular_momentum(d);
    const std::vector<Vec<dim>> v0 = d.momentum;
    const double before = worst_closing(d, thickness, dt, h);
    CHECK(before < -1e-6);  // without contact, pairs would close below the thickness
    const domains::SurfaceContactResult r = domains::surface_contact(d, dt, thickness);
    CHECK(r.contacts > 0);
    CHECK(r.contacts <= r.pairs);
    CHECK((total_momentum(d) - p0).norm() < 1e-14 * d.corner_count());
    CHECK((angular_momentum(d) - l0).norm() < 1e-14 * d.corner_count());
    CHECK(worst_closing(d, thickness, dt, h) > -1e-12);
    for (std::size_t c = 0; c < d.corner_count(); ++c)  // the FLIP increments carry the same change
      CHECK((d.force[c] - (d.momentum[c] - v0[c])).norm() < 1e-12 * (1.0 + v0[c].norm()));
  }
}
TEST_CASE_TEMPLATE("surface contact: separating pairs and unenriched corners are left alone", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  std::mt19937 rng(11);
  const double h = 0.01, dt = 1e-3;
  {  // the block moves away from the slab
    domains::ParticleDomains<dim> d = two_bodies<dim>(h, 0.05 * h, -1.0, rng);
    for (std::size_t c = 0; c < d.corner_count(); ++c) d.momentum[c] = Vec<dim>::Unit(dim - 1) * (d.x[c][dim - 1] > h);
    const std::vector<Vec<dim>> v0 = d.momentum;
    const domains::SurfaceContactResult r = domains::surface_contact(d, dt, 0.1 * h);
    CHECK(r.pairs > 0);
    CHECK(r.contacts == 0);
    CHECK(d.momentum == v0);
  }
  {  // closing, but no corner enriched: the grid keeps these apart
    domains::ParticleDomains<dim> d = two_bodies<dim>(h, 0.05 * h, 1.0, rng);
    d.enriched.assign(d.corner_count(), 0);
    const std::vector<Vec<dim>> v0 = d.momentum;
    CHECK(domains::surface_contact(d, dt, 0.1 * h).pairs == 0);
    CHECK(d.momentum == v0);
    d.enriched.clear();  // a scene without enrichment
    CHECK(domains::surface_contact(d, dt, 0.1 * h).pairs == 0);
    CHECK(d.momentum == v0);
  }
  {  // corners of one body are never paired with its own faces (elasticity keeps them apart)
    domains::ParticleDomains<dim> d = two_bodies<dim>(h, 10.0 * h, 1.0, rng);
    CHECK(domains::surface_contact(d, dt, 0.1 * h).pairs == 0);
  }
  domains::ParticleDomains<dim> d = two_bodies<dim>(h, h, 1.0, rng);
  CHECK_THROWS_AS(domains::surface_contact(d, dt, 0.0), Error);
  CHECK_THROWS_AS(domains::surface_contact(d, 0.0, 0.1 * h), Error);
}
