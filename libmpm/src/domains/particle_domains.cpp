// Particle domains: corners shared on the seeding lattice, and the corner <-> grid transfers
// (equations in particle_domains.h). The corners take the place of particles in the bucketed
// loops of the uniform transfers (core/detail/bucket_loops.h): a corner is a point, so its
// weights are the scene kernel's at the corner.
#include <mpm/core/detail/transfer_loops.h>
#include <mpm/core/error.h>
#include <mpm/domains/particle_domains.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <Eigen/LU>  // determinant

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <unordered_map>

namespace mpm::domains {

using detail::ChannelView;
using detail::PatchFrame;
using detail::Stencil;

template <int dim>
std::size_t ParticleDomains<dim>::memory_bytes() const {
  return x.capacity() * sizeof(Vec<dim>) + corner_of.capacity() * sizeof(corner_of[0]) +
         inverse_side.capacity() * sizeof(Vec<dim>) +
         (sharing_begin.capacity() + sharing.capacity()) * sizeof(std::uint32_t) +
         surface.capacity() * sizeof(surface[0]) + buckets.memory_bytes() + mass.capacity() * sizeof(double) +
         (momentum.capacity() + force.capacity()) * sizeof(Vec<dim>) + enriched.capacity() + point.capacity() +
         velocity_gradient.capacity() * sizeof(Mat<dim>) + embedded_domain.capacity() * sizeof(std::uint32_t) +
         embedded_local.capacity() * sizeof(Vec<dim>) + embedded_triangles.capacity() * sizeof(embedded_triangles[0]);
}

template <int dim>
void add_body(ParticleDomains<dim>& domains, std::size_t first, const std::vector<Vec<dim>>& positions, double spacing,
              const Vec<dim>& stretch) {
  MPM_VERIFY(first == domains.particle_count(), Error,
             "particle domains: particles must get their domains in the order they were added");
  MPM_VERIFY(spacing > 0.0 && (stretch.array().abs() > 0.0).all(), Error,
             "particle domains: the lattice spacing and every stretch must be nonzero");
  if (positions.empty()) return;
  Vec<dim> lo = positions.front();
  for (const Vec<dim>& x : positions) lo = lo.cwiseMin(x);
  // Lattice cell of each particle, and a key per corner of the corner lattice (21 bits an axis).
  constexpr int bits = 63 / dim;
  std::unordered_map<std::uint64_t, std::uint32_t> corner_at;
  for (const Vec<dim>& x : positions) {
    IVec<dim> cell;
    for (int a = 0; a < dim; ++a) {
      const double u = (x[a] - lo[a]) / spacing;
      cell[a] = static_cast<int>(std::lround(u));
      if (std::fabs(u - cell[a]) > 1e-6 || cell[a] + std::int64_t{1} >= (std::int64_t{1} << bits))
        throw Error("particle domains: the particle at offset " + std::to_string(u) + " spacings along axis " +
                    std::to_string(a) + " is not on the body's seeding lattice (domains need lattice-seeded bodies)");
    }
    std::array<std::uint32_t, ParticleDomains<dim>::corners> own;
    for (int alpha = 0; alpha < ParticleDomains<dim>::corners; ++alpha) {
      std::uint64_t key = 0;
      Vec<dim> corner;
      for (int a = dim - 1; a >= 0; --a) {
        const int c = cell[a] + ((alpha >> a) & 1);
        key = (key << bits) | static_cast<std::uint64_t>(c);
        corner[a] = lo[a] + (c - 0.5) * spacing;
      }
      const auto [it, added] = corner_at.try_emplace(key, static_cast<std::uint32_t>(domains.x.size()));
      if (added) {
        domains.x.push_back(corner);
        domains.point.push_back(0);
      }
      own[alpha] = it->second;
    }
    domains.corner_of.push_back(own);
    domains.inverse_side.push_back(stretch / spacing);
  }
}

template <int dim>
void embed_mesh(ParticleDomains<dim>& domains, std::size_t first, const std::vector<Vec<dim>>& positions,
                double spacing, const std::vector<Vec<dim>>& vertices,
                const std::vector<std::array<std::uint32_t, 3>>& triangles) {
  MPM_VERIFY(first + positions.size() <= domains.particle_count() && spacing > 0.0, Error,
             "particle domains: a mesh is embedded in the domains of a body added before");
  if (positions.empty()) return;
  // The body's lattice as add_body laid it: particle cell i spans u in [i - 1/2, i + 1/2] of
  // u = (x - lo) / spacing. Cells are keyed with an offset of `margin`, so that the cells a
  // vertex outside the body searches (down to -margin) have keys too.
  constexpr int margin = 4, bits = 63 / dim;
  Vec<dim> lo = positions.front();
  for (const Vec<dim>& x : positions) lo = lo.cwiseMin(x);
  const auto key = [&](const IVec<dim>& cell) {
    std::uint64_t k = 0;
    for (int a = dim - 1; a >= 0; --a) k = (k << bits) | static_cast<std::uint64_t>(cell[a] + margin);
    return k;
  };
  std::unordered_map<std::uint64_t, std::uint32_t> particle_at;
  for (std::size_t p = 0; p < positions.size(); ++p) {
    IVec<dim> cell;
    for (int a = 0; a < dim; ++a) cell[a] = static_cast<int>(std::lround((positions[p][a] - lo[a]) / spacing));
    particle_at.emplace(key(cell), static_cast<std::uint32_t>(first + p));
  }
  const std::uint32_t base = static_cast<std::uint32_t>(domains.embedded_domain.size());
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const Vec<dim> u = (vertices[v] - lo) / spacing;
    IVec<dim> home;
    for (int a = 0; a < dim; ++a) home[a] = static_cast<int>(std::floor(u[a] + 0.5));
    // The cell that holds the vertex, else the nearest particle centre within two cells (none
    // when the vertex is beyond the keyed cells).
    std::uint32_t particle = 0;
    IVec<dim> best_cell = home;
    double best = std::numeric_limits<double>::infinity();
    bool keyed = true;
    for (int a = 0; a < dim; ++a)
      keyed = keyed && home[a] >= 2 - margin && home[a] + 2 + margin < (std::int64_t{1} << bits);
    constexpr int side = 5, cells = dim == 2 ? side * side : side * side * side;
    for (int n = 0; keyed && n < cells; ++n) {
      IVec<dim> cell;
      for (int a = 0, m = n; a < dim; ++a, m /= side) cell[a] = home[a] + m % side - side / 2;
      const auto it = particle_at.find(key(cell));
      if (it == particle_at.end()) continue;
      const double distance = cell == home ? -1.0 : (u - cell.template cast<double>()).squaredNorm();
      if (distance < best) best = distance, particle = it->second, best_cell = cell;
    }
    if (!(best < std::numeric_limits<double>::infinity()))
      throw Error("particle domains: mesh vertex " + std::to_string(v) +
                  " lies more than two particle spacings from the body's particles (embed the mesh the body was "
                  "seeded from)");
    domains.embedded_domain.push_back(particle);
    domains.embedded_local.push_back(u - best_cell.template cast<double>() + Vec<dim>::Constant(0.5));
  }
  for (const auto& t : triangles) {
    for (const std::uint32_t i : t)
      MPM_VERIFY(i < vertices.size(), Error,
                 "particle domains: a mesh triangle names vertex " + std::to_string(i) + " of " +
                     std::to_string(vertices.size()));
    domains.embedded_triangles.push_back({base + t[0], base + t[1], base + t[2]});
  }
}

template <int dim>
void add_points(ParticleDomains<dim>& domains, std::size_t first, const std::vector<Vec<dim>>& positions) {
  MPM_VERIFY(first == domains.particle_count(), Error,
             "particle domains: particles must get their domains in the order they were added");
  for (const Vec<dim>& x : positions) {
    std::array<std::uint32_t, ParticleDomains<dim>::corners> own;
    own.fill(static_cast<std::uint32_t>(domains.x.size()));
    domains.x.push_back(x);
    domains.point.push_back(1);
    domains.corner_of.push_back(own);
    domains.inverse_side.push_back(Vec<dim>::Zero());  // no reference box: grad_X w_alpha_p = 0
  }
  domains.point_count += positions.size();
}

namespace {
//! The faces of every domain that no other domain has (surface above). Face (a, side) of a
//! domain holds the corners whose bit a is `side`, taken around the face in the order of the
//! other axes (b, c) = (a + 1, a + 2) mod dim, so that e_b x e_c = e_a: outward for side 1,
//! reversed for side 0. In 2D the edge runs along the other axis b, counter-clockwise.
template <int dim>
void find_surface(ParticleDomains<dim>& d) {
  constexpr int K = ParticleDomains<dim>::corners / 2;
  using Face = std::array<std::uint32_t, K>;
  std::map<Face, std::pair<int, Face>> seen;  // sorted corners -> (count, oriented face)
  for (const auto& own : d.corner_of)
    for (int a = 0; a < dim && !d.point[own[0]]; ++a)
      for (int side = 0; side < 2; ++side) {
        Face face;
        for (int k = 0; k < K; ++k) {
          // k walks the face: in 3D (0,0), (1,0), (1,1), (0,1) over the axes (b, c).
          const int u = dim == 2 ? k : (k == 1 || k == 2), w = dim == 2 ? 0 : k / 2;
          const int b = (a + 1) % dim, c = (a + 2) % dim;
          face[k] = own[(side << a) | (u << b) | (dim == 3 ? w << c : 0)];
        }
        const bool reverse = dim == 2 ? (side == 0) != (a == 1) : side == 0;
        if (reverse) std::reverse(face.begin(), face.end());
        Face key = face;
        std::sort(key.begin(), key.end());
        auto& [count, oriented] = seen[key];
        if (count++ == 0) oriented = face;
      }
  d.surface.clear();
  for (const auto& [key, entry] : seen)
    if (entry.first == 1) d.surface.push_back(entry.second);
}
}  // namespace

template <int dim>
void index_sharing(ParticleDomains<dim>& d) {
  find_surface(d);
  constexpr int K = ParticleDomains<dim>::corners;
  d.sharing_begin.assign(d.corner_count() + 1, 0);
  for (const auto& own : d.corner_of)
    for (const std::uint32_t c : own) ++d.sharing_begin[c + 1];
  for (std::size_t c = 0; c < d.corner_count(); ++c) d.sharing_begin[c + 1] += d.sharing_begin[c];
  d.sharing.resize(d.particle_count() * K);
  std::vector<std::uint32_t> next(d.sharing_begin.begin(), d.sharing_begin.end() - 1);
  for (std::size_t p = 0; p < d.particle_count(); ++p)
    for (int alpha = 0; alpha < K; ++alpha)
      d.sharing[next[d.corner_of[p][alpha]]++] = static_cast<std::uint32_t>(p * K + alpha);
}

namespace {
//! cof F = det(F) F^-T, defined for a singular F too.
template <int dim>
Mat<dim> cofactor(const Mat<dim>& F) {
  Mat<dim> c;
  if constexpr (dim == 2) {
    c << F(1, 1), -F(1, 0), -F(0, 1), F(0, 0);
  } else {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        c(i, j) = F((i + 1) % 3, (j + 1) % 3) * F((i + 2) % 3, (j + 2) % 3) -
                  F((i + 1) % 3, (j + 2) % 3) * F((i + 2) % 3, (j + 1) % 3);
  }
  return c;
}

//! The current thickness of particle p's domain across its reference axes, the smallest of
//! volume over the area of the opposite face, J L_a / |J F^-T e_a| = L_a |det F| / |cof(F) e_a|
//! (Nanson), and the axis of it.
template <int dim>
std::pair<double, int> thinnest(const ParticleDomains<dim>& d, std::size_t p, const Mat<dim>& F) {
  const Mat<dim> c = cofactor<dim>(F);
  const double J = std::fabs(F.determinant());
  std::pair<double, int> result{std::numeric_limits<double>::infinity(), 0};
  for (int a = 0; a < dim; ++a) {
    const double area = c.col(a).norm();
    const double h = area > 0.0 ? J / (std::fabs(d.inverse_side[p][a]) * area) : 0.0;
    if (h < result.first) result = {h, a};
  }
  return result;
}
}  // namespace

// K(F) = sigma_min / sigma_max, the reciprocal of F's condition number in the 2-norm, which is
// what Zhu et al. sec. 5.1 describe ("reciprocal of the condition number", "in the range of 0 to
// 1"); their eq. 10 prints Frobenius norms, with which a rotation would give 1/dim and every
// particle be enriched at epsilon = 0.6. From the eigenvalues of C = F^T F (sigma^2), in
// closed form: a quarter of the cost of the SVD (88 against 350 ns in 3D, docs/performance.md),
// which every particle needs every step.
// The largest eigenvalue comes from the trigonometric formula for symmetric 3x3 matrices; the
// smallest from det C = det(F)^2 over the two larger ones, so a thin domain keeps its relative
// accuracy. Where two eigenvalues coincide the arccosine costs digits: K to about 1e-8.
template <int dim>
double enrichment_metric(const Mat<dim>& F) {
  const Mat<dim> C = F.transpose() * F;
  const double det2 = F.determinant() * F.determinant();
  if constexpr (dim == 2) {
    const double largest = 0.5 * C.trace() + std::hypot(0.5 * (C(0, 0) - C(1, 1)), C(0, 1));
    return largest > 0.0 ? std::sqrt(det2) / largest : 0.0;  // sqrt(lambda_min / lambda_max)
  } else {
    const double q = C.trace() / 3.0;
    if (!(q > 0.0)) return 0.0;
    const double off = C(0, 1) * C(0, 1) + C(0, 2) * C(0, 2) + C(1, 2) * C(1, 2);
    const double p = std::sqrt(((C.diagonal().array() - q).square().sum() + 2.0 * off) / 6.0);
    if (p <= 1e-15 * q) return 1.0;  // C = q I: a rotation times a uniform scaling
    const double r = std::clamp((C - q * Mat<dim>::Identity()).determinant() / (2.0 * p * p * p), -1.0, 1.0);
    const double angle = std::acos(r) / 3.0;
    const double largest = q + 2.0 * p * std::cos(angle);
    const double smallest_guess = q + 2.0 * p * std::cos(angle + 2.0 * std::numbers::pi / 3.0);
    const double middle = std::max(3.0 * q - largest - smallest_guess, 0.0);
    if (!(middle > 0.0)) return 0.0;
    return std::sqrt(det2 / (largest * middle) / largest);
  }
}

template <int dim>
void mark_enrichment(ParticleDomains<dim>& d, const std::vector<Mat<dim>>& F, bool explicit_step) {
  MPM_VERIFY(F.size() == d.particle_count(), Error, "particle domains: enrichment needs F of every particle");
  d.enriched_particles = 0;
  d.enriched_length = std::numeric_limits<double>::infinity();
  if (d.enrichment_threshold <= 0.0) {
    d.enriched.clear();
    return;
  }
  // Per particle first, then per corner over the particles sharing it: no two threads write
  // one flag.
  std::vector<std::uint8_t> particle_enriched(d.particle_count());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.particle_count(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p)
      particle_enriched[p] = !d.is_point(p) && enrichment_metric<dim>(F[p]) <= d.enrichment_threshold;
  });
  constexpr int K = ParticleDomains<dim>::corners;
  d.enriched.resize(d.corner_count());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.corner_count(), 4096), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      std::uint8_t any = 0;
      for (std::uint32_t k = d.sharing_begin[c]; k != d.sharing_begin[c + 1]; ++k)
        any |= particle_enriched[d.sharing[k] / K];
      d.enriched[c] = any;
    }
  });
  for (const std::uint8_t e : particle_enriched) d.enriched_particles += e;
  if (d.enriched_particles == 0 || !explicit_step) return;
  const auto touches_enriched = [&](std::size_t p) {
    for (const std::uint32_t c : d.corner_of[p])
      if (d.enriched[c]) return true;
    return false;
  };
  // A flat enriched domain (thinner than 1e-6 of its rest size) has no stable explicit step.
  const auto flat = [&](std::size_t p, double h, int axis) { return !(h > 1e-6 / std::fabs(d.inverse_side[p][axis])); };
  std::atomic<bool> any_flat{false};
  d.enriched_length = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, d.particle_count(), 4096), std::numeric_limits<double>::infinity(),
      [&](const auto& r, double length) {
        for (std::size_t p = r.begin(); p != r.end(); ++p) {
          if (!touches_enriched(p)) continue;
          const auto [h, axis] = thinnest(d, p, F[p]);
          if (flat(p, h, axis)) any_flat.store(true, std::memory_order_relaxed);
          length = std::min(length, h);
        }
        return length;
      },
      [](double a, double b) { return std::min(a, b); });
  // Name the first flat one (the same for any thread count) rather than crawl at dt -> 0.
  if (any_flat.load())
    for (std::size_t p = 0; p < d.particle_count(); ++p) {
      const auto [h, axis] = thinnest(d, p, F[p]);
      if (touches_enriched(p) && flat(p, h, axis))
        throw NumericalError("stage 'enrichment': the domain of particle " + std::to_string(p) + " is flat (" +
                             std::to_string(h) + " m across reference axis " + std::to_string(axis) +
                             ", below 1e-6 of its rest size): enriched corners cannot be stepped explicitly "
                             "through it; lower domain_enrichment or remove it");
    }
}

template <int dim>
void corners_to_grid(ParticleDomains<dim>& d, const Kernel& kernel, SparseGrid<dim>& grid, const std::string& stage,
                     const std::vector<Mat<dim>>& point_stress) {
  sort_into_buckets<dim, double>(d.x, kernel, grid, d.buckets, {}, stage);
  const std::size_t n = grid.node_storage();
  std::fill(grid.mass.begin(), grid.mass.end(), 0.0);
  std::fill(grid.velocity.begin(), grid.velocity.end(), Vec<dim>::Zero());
  grid.force.assign(n, Vec<dim>::Zero());
  constexpr int Ch = 1 + 2 * dim;  // mass, momentum, force
  std::array<ChannelView, Ch> channels;
  channels[0] = detail::scalar_view(grid.mass);
  for (int a = 0; a < dim; ++a) {
    channels[1 + a] = detail::component_view<dim>(grid.velocity, a);
    channels[1 + dim + a] = detail::component_view<dim>(grid.force, a);
  }
  using Node = Eigen::Matrix<double, Ch, 1>;
  MPM_VERIFY(d.point_count == 0 || point_stress.size() == d.particle_count(), Error,
             "stage '" + stage + "': the material points' stress is not set");
  const double inv_dx = 1.0 / grid.dx();
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::scatter<dim, Ch>(
            grid, d.buckets, channels, [&](std::uint32_t c, const PatchFrame<dim>& f, double* patch) {
              if (!d.enriched.empty() && d.enriched[c]) return;  // stops at the corner
              Stencil<dim, K::support> st;
              Node values[dim + 1];
              for (Node& v : values) v.setZero();
              values[0] << d.mass[c], d.momentum[c], d.force[c];
              if (!d.point[c]) {
                st.template compute<false>(k, f.cells(d.x[c]), f.origin);
                detail::spread<false>(st, values, patch);
                return;
              }
              // A material point: its stress as standard MPM scatters it.
              st.compute(k, f.cells(d.x[c]), f.origin);
              detail::spread<false>(st, values, patch);
              detail::spread_gradient<Ch>(st, Mat<dim>(-inv_dx * point_stress[d.point_particle(c)]), patch, 1 + dim);
            });
      },
      kernel);
}

template <int dim>
void grid_to_corners(ParticleDomains<dim>& d, const Kernel& kernel, const SparseGrid<dim>& grid, bool flip) {
  const double inv_dx = 1.0 / grid.dx();
  const auto run = [&](auto channel_count) {
    constexpr int Ch = decltype(channel_count)::value;
    std::array<ChannelView, Ch> channels;
    for (int a = 0; a < dim; ++a) channels[a] = detail::component_view<dim>(grid.velocity, a);
    if constexpr (Ch == 2 * dim)
      for (int a = 0; a < dim; ++a) channels[dim + a] = detail::component_view<dim>(grid.velocity_old, a);
    std::visit(
        [&](const auto& k) {
          using K = std::decay_t<decltype(k)>;
          detail::gather<dim, Ch>(grid, d.buckets, channels,
                                  [&](std::uint32_t c, const PatchFrame<dim>& f, const double* patch) {
                                    if (!d.enriched.empty() && d.enriched[c]) return;
                                    Stencil<dim, K::support> st;
                                    const bool point = d.point[c];
                                    if (point)
                                      st.compute(k, f.cells(d.x[c]), f.origin);
                                    else
                                      st.template compute<false>(k, f.cells(d.x[c]), f.origin);
                                    Vec<dim> v = Vec<dim>::Zero(), dv = Vec<dim>::Zero();
                                    Mat<dim> grad_v = Mat<dim>::Zero();
                                    st.for_each_node([&](int node, double w, const Vec<dim>& grad, const Vec<dim>&) {
                                      const Eigen::Map<const Vec<dim>> vi(patch + node * Ch);
                                      v.noalias() += w * vi;
                                      if constexpr (Ch == 2 * dim)
                                        dv.noalias() += w * (vi - Eigen::Map<const Vec<dim>>(patch + node * Ch + dim));
                                      if (point) grad_v.noalias() += vi * grad.transpose();
                                    });
                                    d.momentum[c] = v;
                                    d.force[c] = dv;
                                    if (point) d.velocity_gradient[c] = grad_v * inv_dx;
                                  });
        },
        kernel);
  };
  d.momentum.resize(d.corner_count());
  d.force.resize(d.corner_count());
  if (d.point_count) d.velocity_gradient.resize(d.corner_count());
  if (flip)
    run(std::integral_constant<int, 2 * dim>{});
  else
    run(std::integral_constant<int, dim>{});
}

template <int dim>
void corner_forces(const ParticleDomains<dim>& d, const std::vector<Mat<dim>>& weighted_stress,
                   std::vector<Vec<dim>>& out) {
  constexpr int K = ParticleDomains<dim>::corners;
  out.resize(d.corner_count());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.corner_count(), 4096), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      Vec<dim> f = Vec<dim>::Zero();
      for (std::uint32_t k = d.sharing_begin[c]; k != d.sharing_begin[c + 1]; ++k) {
        const std::size_t p = d.sharing[k] / K;
        f.noalias() -= weighted_stress[p] * d.weight_gradient(p, static_cast<int>(d.sharing[k] % K));
      }
      out[c] = f;
    }
  });
}

template <int dim>
void corners_from_nodes(const ParticleDomains<dim>& d, const Kernel& kernel, const SparseGrid<dim>& grid,
                        const std::vector<Vec<dim>>& u, std::vector<Vec<dim>>& out) {
  out.resize(d.corner_count(), Vec<dim>::Zero());
  std::array<ChannelView, dim> channels;
  for (int a = 0; a < dim; ++a) channels[a] = detail::component_view<dim>(u, a);
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::gather<dim, dim>(grid, d.buckets, channels,
                                 [&](std::uint32_t c, const PatchFrame<dim>& f, const double* patch) {
                                   if (!d.enriched.empty() && d.enriched[c]) return;
                                   Stencil<dim, K::support> st;
                                   st.template compute<false>(k, f.cells(d.x[c]), f.origin);
                                   Vec<dim> v = Vec<dim>::Zero();
                                   st.for_each_node([&](int node, double w, const Vec<dim>&, const Vec<dim>&) {
                                     v.noalias() += w * Eigen::Map<const Vec<dim>>(patch + node * dim);
                                   });
                                   out[c] = v;
                                 });
      },
      kernel);
}

template <int dim>
void nodes_from_corners(const ParticleDomains<dim>& d, const Kernel& kernel, const SparseGrid<dim>& grid,
                        const std::vector<Vec<dim>>& f, std::vector<Vec<dim>>& out) {
  out.assign(grid.node_storage(), Vec<dim>::Zero());
  std::array<ChannelView, dim> channels;
  for (int a = 0; a < dim; ++a) channels[a] = detail::component_view<dim>(out, a);
  using Node = Vec<dim>;
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::scatter<dim, dim>(grid, d.buckets, channels,
                                  [&](std::uint32_t c, const PatchFrame<dim>& frame, double* patch) {
                                    if (!d.enriched.empty() && d.enriched[c]) return;
                                    Stencil<dim, K::support> st;
                                    st.template compute<false>(k, frame.cells(d.x[c]), frame.origin);
                                    Node values[dim + 1];
                                    for (Node& v : values) v.setZero();
                                    values[0] = f[c];
                                    detail::spread<false>(st, values, patch);
                                  });
      },
      kernel);
}

template <int dim>
void for_each_two_step_gradient(const ParticleDomains<dim>& d, const Kernel& kernel, const SparseGrid<dim>& grid,
                                const std::function<void(std::size_t, Index, const Vec<dim>&)>& body) {
  constexpr int K = ParticleDomains<dim>::corners;
  // Per particle, q on the box of nodes its corners' stencils span (dense, so no search).
  std::vector<Vec<dim>> q;
  std::vector<std::uint8_t> touched;
  std::visit(
      [&](const auto& k) {
        using Kern = std::decay_t<decltype(k)>;
        constexpr int S = Kern::support;
        std::array<std::array<int, dim>, K> base;
        std::array<std::array<std::array<double, S>, dim>, K> w;
        for (std::size_t p = 0; p < d.particle_count(); ++p) {
          IVec<dim> lo = IVec<dim>::Constant(std::numeric_limits<int>::max()), hi = -lo;
          bool any = false;
          for (int alpha = 0; alpha < K; ++alpha) {
            const std::uint32_t c = d.corner_of[p][alpha];
            if (!d.enriched.empty() && d.enriched[c]) continue;
            any = true;
            double dw[S];
            for (int a = 0; a < dim; ++a) {
              k((d.x[c][a] - grid.origin()[a]) / grid.dx(), base[alpha][a], w[alpha][a].data(), dw);
              lo[a] = std::min(lo[a], base[alpha][a]);
              hi[a] = std::max(hi[a], base[alpha][a] + S - 1);
            }
          }
          if (!any) continue;
          const IVec<dim> extent = hi - lo + IVec<dim>::Ones();
          const auto flat = [&](const IVec<dim>& node) {
            std::size_t i = 0;
            for (int a = dim - 1; a >= 0; --a) i = i * extent[a] + (node[a] - lo[a]);
            return i;
          };
          q.assign(static_cast<std::size_t>(extent.prod()), Vec<dim>::Zero());
          touched.assign(q.size(), 0);
          for (int alpha = 0; alpha < K; ++alpha) {
            const std::uint32_t c = d.corner_of[p][alpha];
            if (!d.enriched.empty() && d.enriched[c]) continue;
            const Vec<dim> g = d.weight_gradient(p, alpha);
            for (int t = 0; t < ipow(S, dim); ++t) {
              IVec<dim> node;
              double weight = 1.0;
              for (int a = 0, rest = t; a < dim; ++a, rest /= S) {
                node[a] = base[alpha][a] + rest % S;
                weight *= w[alpha][a][rest % S];
              }
              const std::size_t i = flat(node);
              q[i] += weight * g;
              touched[i] = 1;
            }
          }
          for (std::size_t i = 0; i < q.size(); ++i) {
            if (!touched[i]) continue;
            IVec<dim> node;
            std::size_t rest = i;
            for (int a = 0; a < dim; ++a) {
              node[a] = lo[a] + static_cast<int>(rest % extent[a]);
              rest /= extent[a];
            }
            body(p, grid.node_index(node), q[i]);
          }
        }
      },
      kernel);
}

template <int dim>
void integrate_enriched(ParticleDomains<dim>& d, double dt, const Vec<dim>& gravity,
                        const std::function<void(const Vec<dim>&, Vec<dim>&)>& constrain) {
  if (d.enriched.empty()) return;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.corner_count(), 4096), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      if (!d.enriched[c]) continue;
      const Vec<dim> v_old = d.momentum[c] / d.mass[c];
      Vec<dim> v = v_old + dt * (d.force[c] / d.mass[c] + gravity);
      constrain(d.x[c], v);
      d.momentum[c] = v;
      d.force[c] = v - v_old;
    }
  });
}

template <int dim>
void advance_corners(ParticleDomains<dim>& d, double dt) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.corner_count(), 4096), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) d.x[c] += dt * d.momentum[c];
  });
}

template <int dim>
CarriedData carried(const ParticleDomains<dim>& d) {
  std::vector<double> flat(d.corner_count() * dim);
  for (std::size_t c = 0; c < d.corner_count(); ++c)
    for (int a = 0; a < dim; ++a) flat[c * dim + a] = d.x[c][a];
  return {{"domains/x", std::move(flat)}};
}

template <int dim>
void restore(ParticleDomains<dim>& d, const CarriedData& data) {
  for (const auto& [name, values] : data) {
    if (name != "domains/x") continue;
    MPM_VERIFY(values.size() == d.corner_count() * dim, InputError,
               "particle domains: the checkpoint holds " + std::to_string(values.size() / dim) +
                   " domain corners, the scene seeds " + std::to_string(d.corner_count()));
    for (std::size_t c = 0; c < d.corner_count(); ++c)
      for (int a = 0; a < dim; ++a) d.x[c][a] = values[c * dim + a];
    return;
  }
  throw InputError(
      "particle domains: the checkpoint holds no domain corners (written by a scene without particle_domains)");
}

#define MPM_INSTANTIATE(dim)                                                                                         \
  template struct ParticleDomains<dim>;                                                                              \
  template void add_body(ParticleDomains<dim>&, std::size_t, const std::vector<Vec<dim>>&, double, const Vec<dim>&); \
  template void add_points(ParticleDomains<dim>&, std::size_t, const std::vector<Vec<dim>>&);                        \
  template void embed_mesh(ParticleDomains<dim>&, std::size_t, const std::vector<Vec<dim>>&, double,                 \
                           const std::vector<Vec<dim>>&, const std::vector<std::array<std::uint32_t, 3>>&);          \
  template void index_sharing(ParticleDomains<dim>&);                                                                \
  template void corners_to_grid(ParticleDomains<dim>&, const Kernel&, SparseGrid<dim>&, const std::string&,          \
                                const std::vector<Mat<dim>>&);                                                       \
  template double enrichment_metric<dim>(const Mat<dim>&);                                                           \
  template void mark_enrichment(ParticleDomains<dim>&, const std::vector<Mat<dim>>&, bool);                          \
  template void grid_to_corners(ParticleDomains<dim>&, const Kernel&, const SparseGrid<dim>&, bool);                 \
  template void integrate_enriched(ParticleDomains<dim>&, double, const Vec<dim>&,                                   \
                                   const std::function<void(const Vec<dim>&, Vec<dim>&)>&);                          \
  template void corner_forces(const ParticleDomains<dim>&, const std::vector<Mat<dim>>&, std::vector<Vec<dim>>&);    \
  template void corners_from_nodes(const ParticleDomains<dim>&, const Kernel&, const SparseGrid<dim>&,               \
                                   const std::vector<Vec<dim>>&, std::vector<Vec<dim>>&);                            \
  template void nodes_from_corners(const ParticleDomains<dim>&, const Kernel&, const SparseGrid<dim>&,               \
                                   const std::vector<Vec<dim>>&, std::vector<Vec<dim>>&);                            \
  template void for_each_two_step_gradient(const ParticleDomains<dim>&, const Kernel&, const SparseGrid<dim>&,       \
                                           const std::function<void(std::size_t, Index, const Vec<dim>&)>&);         \
  template void advance_corners(ParticleDomains<dim>&, double);                                                      \
  template CarriedData carried(const ParticleDomains<dim>&);                                                         \
  template void restore(ParticleDomains<dim>&, const CarriedData&);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm::domains
