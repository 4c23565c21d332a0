// Self-contact of enriched particle domains (equations in surface_contact.h). Broad phase: the
// vertices sorted into a hashed cell lattice, each face visiting the cells of its box widened
// by the reach of the step; narrow phase: the closest point of the face to each vertex there.
#include <mpm/core/error.h>
#include <mpm/domains/surface_contact.h>

#include <tbb/parallel_for.h>
#include <Eigen/Geometry>  // cross

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace mpm::domains {

namespace {

constexpr int kMaxFaceCorners = 4;

//! The point of a face closest to x as barycentric weights over the face's corners (in the
//! order of ParticleDomains::surface), and the face's outward normal there (for a vertex on
//! the face, where x - x_f has no direction).
template <int dim>
struct Closest {
  std::array<double, kMaxFaceCorners> b{};
  Vec<dim> point;
  Vec<dim> normal;
};

//! Closest point of segment ab to x; the outward normal of a counter-clockwise boundary edge.
Closest<2> closest_on_segment(const Vec<2>& x, const Vec<2>& a, const Vec<2>& b) {
  const Vec<2> e = b - a;
  const double length2 = e.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((x - a).dot(e) / length2, 0.0, 1.0) : 0.0;
  Closest<2> c;
  c.b[0] = 1.0 - t;
  c.b[1] = t;
  c.point = a + t * e;
  c.normal = length2 > 0.0 ? Vec<2>(Vec<2>(e[1], -e[0]) / std::sqrt(length2)) : Vec<2>::UnitY();
  return c;
}

//! Closest point of triangle abc to x by the Voronoi regions of its vertices, edges and face
//! (Ericson, Real-Time Collision Detection, sec. 5.1.5); weights of (a, b, c).
std::array<double, 3> closest_on_triangle(const Vec<3>& x, const Vec<3>& a, const Vec<3>& b, const Vec<3>& c) {
  const Vec<3> ab = b - a, ac = c - a, ax = x - a;
  const double d1 = ab.dot(ax), d2 = ac.dot(ax);
  if (d1 <= 0.0 && d2 <= 0.0) return {1.0, 0.0, 0.0};
  const Vec<3> bx = x - b;
  const double d3 = ab.dot(bx), d4 = ac.dot(bx);
  if (d3 >= 0.0 && d4 <= d3) return {0.0, 1.0, 0.0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {1.0 - v, v, 0.0};
  }
  const Vec<3> cx = x - c;
  const double d5 = ab.dot(cx), d6 = ac.dot(cx);
  if (d6 >= 0.0 && d5 <= d6) return {0.0, 0.0, 1.0};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {1.0 - w, 0.0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0.0, 1.0 - w, w};
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) return {1.0, 0.0, 0.0};  // a degenerate triangle: its first corner
  const double v = vb / sum, w = vc / sum;
  return {1.0 - v - w, v, w};
}

//! Closest point of the quadrilateral (as triangles 0,1,2 and 0,2,3) to x.
Closest<3> closest_on_quad(const Vec<3>& x, const std::array<Vec<3>, 4>& q) {
  Closest<3> best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const std::array<int, 3> t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
    const std::array<double, 3> w = closest_on_triangle(x, q[t[0]], q[t[1]], q[t[2]]);
    const Vec<3> point = w[0] * q[t[0]] + w[1] * q[t[1]] + w[2] * q[t[2]];
    const double distance = (x - point).squaredNorm();
    if (distance >= best_distance) continue;
    best_distance = distance;
    best.b = {};
    for (int k = 0; k < 3; ++k) best.b[t[k]] = w[k];
    best.point = point;
    const Vec<3> normal = (q[t[1]] - q[t[0]]).cross(q[t[2]] - q[t[0]]);
    best.normal = normal.norm() > 0.0 ? Vec<3>(normal.normalized()) : Vec<3>::UnitZ();
  }
  return best;
}

template <int dim, std::size_t K>
Closest<dim> closest_on_face(const Vec<dim>& x, const std::vector<Vec<dim>>& corners,
                             const std::array<std::uint32_t, K>& face) {
  if constexpr (dim == 2)
    return closest_on_segment(x, corners[face[0]], corners[face[1]]);
  else
    return closest_on_quad(x, {corners[face[0]], corners[face[1]], corners[face[2]], corners[face[3]]});
}

//! A vertex-face pair within reach: fixed geometry for the step, the impulse's direction and
//! inverse effective mass.
template <int dim>
struct Pair {
  std::uint32_t vertex, face;
  std::array<double, kMaxFaceCorners> b;
  Vec<dim> n;
  double gap, inverse_mass;
};

//! True when corner c and a corner of `face` are corners of one domain (a vertex of the face
//! itself, or its neighbour across a domain: elasticity, not contact, keeps those apart).
template <int dim, std::size_t K>
bool share_a_domain(const ParticleDomains<dim>& d, std::uint32_t c, const std::array<std::uint32_t, K>& face) {
  constexpr int corners = ParticleDomains<dim>::corners;
  for (std::uint32_t k = d.sharing_begin[c]; k != d.sharing_begin[c + 1]; ++k)
    for (const std::uint32_t other : d.corner_of[d.sharing[k] / corners])
      if (std::find(face.begin(), face.end(), other) != face.end()) return true;
  return false;
}

}  // namespace

template <int dim>
SurfaceContactResult surface_contact(ParticleDomains<dim>& d, double dt, double thickness, int sweeps) {
  MPM_VERIFY(thickness > 0.0 && dt > 0.0 && sweeps >= 1, Error,
             "surface contact: the thickness, the step and the sweeps must be positive");
  SurfaceContactResult result;
  if (d.enriched.empty() || std::find(d.enriched.begin(), d.enriched.end(), 1) == d.enriched.end()) return result;
  constexpr std::size_t K = ParticleDomains<dim>::corners / 2;
  const auto& faces = d.surface;
  const std::vector<Vec<dim>>& x = d.x;
  std::vector<Vec<dim>>& v = d.momentum;  // the corner velocities after grid_to_corners

  // The vertices: the surface's corners and the material points' own.
  std::vector<std::uint8_t> is_vertex(d.corner_count(), 0);
  for (const auto& face : faces)
    for (const std::uint32_t c : face) is_vertex[c] = 1;
  for (std::size_t c = 0; c < d.corner_count(); ++c) is_vertex[c] |= d.point[c];
  double speed = 0.0;
  for (std::size_t c = 0; c < d.corner_count(); ++c)
    if (is_vertex[c]) speed = std::max(speed, v[c].norm());
  // A pair can close from at most `reach` to contact within the step.
  const double reach = thickness + 2.0 * dt * speed;

  // Broad phase: the vertices in the cells of a lattice of spacing `cell` (twice the mean face
  // size, at least the reach), as (cell key, vertex) sorted by key; each face then visits the
  // cells that its box, widened by the reach, overlaps.
  if (faces.empty()) return result;
  const auto box_of = [&](const auto& face) {
    std::pair<Vec<dim>, Vec<dim>> box{x[face[0]], x[face[0]]};
    for (const std::uint32_t c : face) box.first = box.first.cwiseMin(x[c]), box.second = box.second.cwiseMax(x[c]);
    return box;
  };
  double extent = 0.0;
  for (const auto& face : faces) {
    const auto [lo, hi] = box_of(face);
    extent += (hi - lo).maxCoeff();
  }
  const double cell = std::max(reach, 2.0 * extent / faces.size());
  constexpr int bits = 63 / dim;
  const auto key = [&](const IVec<dim>& i) {
    std::uint64_t k = 0;
    for (int a = 0; a < dim; ++a)
      k = (k << bits) | (static_cast<std::uint64_t>(i[a]) & ((std::uint64_t{1} << bits) - 1));
    return k;
  };
  const auto cell_of = [&](const Vec<dim>& p) {
    IVec<dim> i;
    for (int a = 0; a < dim; ++a) i[a] = static_cast<int>(std::floor(p[a] / cell));
    return i;
  };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> table;
  for (std::uint32_t c = 0; c < d.corner_count(); ++c)
    if (is_vertex[c] && d.mass[c] > 0.0) table.emplace_back(key(cell_of(x[c])), c);
  std::sort(table.begin(), table.end());

  // Narrow phase: the pairs within reach, in face order, then vertex order; chunks of faces in
  // parallel, joined in chunk order (the same pairs and order at any thread count).
  constexpr std::size_t chunk = 256;
  std::vector<std::vector<Pair<dim>>> found((faces.size() + chunk - 1) / chunk);
  tbb::parallel_for(std::size_t{0}, found.size(), [&](std::size_t n) {
    for (std::size_t f = n * chunk; f < std::min(faces.size(), (n + 1) * chunk); ++f) {
      const auto& face = faces[f];
      const bool enriched_face =
          std::any_of(face.begin(), face.end(), [&](std::uint32_t c) { return d.enriched[c] != 0; });
      auto [lo, hi] = box_of(face);
      lo.array() -= reach;
      hi.array() += reach;
      const IVec<dim> first = cell_of(lo), last = cell_of(hi);
      IVec<dim> i = first;
      while (true) {
        const std::uint64_t k = key(i);
        auto it = std::lower_bound(table.begin(), table.end(), std::pair<std::uint64_t, std::uint32_t>{k, 0});
        for (; it != table.end() && it->first == k; ++it) {
          const std::uint32_t c = it->second;
          if (!enriched_face && !d.enriched[c]) continue;  // the grid keeps those apart
          if (((x[c] - lo).array() < 0.0).any() || ((x[c] - hi).array() > 0.0).any()) continue;
          const Closest<dim> closest = closest_on_face<dim>(x[c], x, face);
          const Vec<dim> offset = x[c] - closest.point;
          const double gap = offset.norm();
          if (gap >= reach || share_a_domain(d, c, face)) continue;
          Pair<dim> pair{c,         static_cast<std::uint32_t>(f),
                         closest.b, gap > 1e-12 * thickness ? Vec<dim>(offset / gap) : closest.normal,
                         gap,       1.0 / d.mass[c]};
          for (std::size_t j = 0; j < K; ++j) pair.inverse_mass += pair.b[j] * pair.b[j] / d.mass[face[j]];
          found[n].push_back(pair);
        }
        int a = 0;
        for (; a < dim && ++i[a] > last[a]; ++a) i[a] = first[a];
        if (a == dim) break;
      }
    }
  });
  std::vector<Pair<dim>> pairs;
  for (const auto& part : found) pairs.insert(pairs.end(), part.begin(), part.end());
  result.pairs = pairs.size();

  // Gauss-Seidel sweeps of the inelastic impulses.
  std::vector<std::uint8_t> touched(pairs.size(), 0);
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    bool any = false;
    for (std::size_t q = 0; q < pairs.size(); ++q) {
      const Pair<dim>& pair = pairs[q];
      const auto& face = faces[pair.face];
      Vec<dim> v_face = Vec<dim>::Zero();
      for (std::size_t j = 0; j < K; ++j) v_face += pair.b[j] * v[face[j]];
      const double v_n = (v[pair.vertex] - v_face).dot(pair.n);
      const double target = std::min(0.0, (thickness - pair.gap) / dt);
      if (v_n >= target - 1e-12 * (std::fabs(target) + thickness / dt)) continue;
      const Vec<dim> impulse = (target - v_n) / pair.inverse_mass * pair.n;
      const Vec<dim> dv = impulse / d.mass[pair.vertex];
      v[pair.vertex] += dv;
      d.force[pair.vertex] += dv;
      for (std::size_t j = 0; j < K; ++j) {
        const Vec<dim> dv_face = -pair.b[j] / d.mass[face[j]] * impulse;
        v[face[j]] += dv_face;
        d.force[face[j]] += dv_face;
      }
      touched[q] = 1;
      any = true;
    }
    if (!any) break;
  }
  result.contacts = static_cast<std::size_t>(std::count(touched.begin(), touched.end(), 1));
  return result;
}

template SurfaceContactResult surface_contact(ParticleDomains<2>&, double, double, int);
template SurfaceContactResult surface_contact(ParticleDomains<3>&, double, double, int);

}  // namespace mpm::domains
