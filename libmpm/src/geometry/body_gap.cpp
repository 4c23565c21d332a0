// The gap between two bodies (body_gap.h): their bounding boxes, then the particles of each
// within reach of the other's box, B's sorted by cell, A's nearest B's box first, each looking in
// the cells within its search radius, which shrinks with the best gap found.
#include <mpm/geometry/body_gap.h>

#include <mpm/core/error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace mpm::geometry {

namespace {

template <int dim>
double half_width(double volume0) {
  return 0.5 * std::pow(volume0, 1.0 / dim);
}

//! A bound of |F^T n| over unit vectors n: the spectral norm is at most sqrt(|F|_1 |F|_inf)
//! (1 for F = I, where the Frobenius norm would give sqrt(dim)).
template <int dim>
double stretch_bound(const Mat<dim>& F) {
  const Mat<dim> A = F.cwiseAbs();
  return std::sqrt(A.colwise().sum().maxCoeff() * A.rowwise().sum().maxCoeff());
}

//! The box of one body's particle centres, its largest reference volume and largest stretch
//! bound (so r() bounds every particle's radius along any direction).
template <int dim>
struct Extent {
  Vec<dim> lo = Vec<dim>::Constant(std::numeric_limits<double>::infinity());
  Vec<dim> hi = Vec<dim>::Constant(-std::numeric_limits<double>::infinity());
  double volume = 0.0, stretch = 1.0;
  bool finite = true;  // every position and F
  bool empty() const { return lo[0] > hi[0]; }
  double r() const { return half_width<dim>(volume) * stretch; }
  void join(const Extent& o) {
    lo = lo.cwiseMin(o.lo);
    hi = hi.cwiseMax(o.hi);
    volume = std::max(volume, o.volume);
    stretch = std::max(stretch, o.stretch);
    finite = finite && o.finite;
  }
  //! Whether x lies in the box grown by `by` on every side.
  bool near(const Vec<dim>& x, double by) const {
    return ((x.array() >= lo.array() - by) && (x.array() <= hi.array() + by)).all();
  }
};

//! The extents of bodies a and b, in one pass over the particles.
template <int dim>
std::array<Extent<dim>, 2> extents(const Particles<dim>& P, const std::vector<Mat<dim>>* F, std::uint16_t a,
                                   std::uint16_t b) {
  using Pair = std::array<Extent<dim>, 2>;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, P.size(), 4096), Pair{},
      [&](const tbb::blocked_range<std::size_t>& range, Pair e) {
        for (std::size_t p = range.begin(); p < range.end(); ++p) {
          const std::uint16_t m = P.material[p];
          if (m != a && m != b) continue;
          Extent<dim>& body = e[m == a ? 0 : 1];
          body.lo = body.lo.cwiseMin(P.x[p]);
          body.hi = body.hi.cwiseMax(P.x[p]);
          body.volume = std::max(body.volume, P.volume0[p]);
          if (F) body.stretch = std::max(body.stretch, stretch_bound<dim>((*F)[p]));
          body.finite = body.finite && P.x[p].allFinite() && (!F || (*F)[p].allFinite());
        }
        return e;
      },
      [](Pair e, const Pair& o) {
        e[0].join(o[0]);
        e[1].join(o[1]);
        return e;
      });
}

//! The particles of a within `by` of b's box, and those of b within `by` of a's, in index order
//! (blocks in parallel, joined in order).
template <int dim>
std::array<std::vector<std::size_t>, 2> near_the_other(const Particles<dim>& P, std::uint16_t a, std::uint16_t b,
                                                       const Extent<dim>& A, const Extent<dim>& B, double by) {
  using Lists = std::array<std::vector<std::size_t>, 2>;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, P.size(), 4096), Lists{},
      [&](const tbb::blocked_range<std::size_t>& range, Lists near) {
        for (std::size_t p = range.begin(); p < range.end(); ++p) {
          if (P.material[p] == a && B.near(P.x[p], by)) near[0].push_back(p);
          if (P.material[p] == b && A.near(P.x[p], by)) near[1].push_back(p);
        }
        return near;
      },
      [](Lists left, const Lists& right) {
        for (int i = 0; i < 2; ++i) left[i].insert(left[i].end(), right[i].begin(), right[i].end());
        return left;
      });
}

}  // namespace

template <int dim>
double body_gap(const Particles<dim>& P, std::uint16_t a, std::uint16_t b, double reach,
                const std::vector<Mat<dim>>* F) {
  verify<InputError>(reach > 0.0 && std::isfinite(reach), "body_gap: the reach must be positive and finite");
  verify<InputError>(!F || F->size() == P.size(), "body_gap: one deformation gradient per particle");
  verify<InputError>(a != b, "body_gap: the two bodies must be of different materials");
  const auto [A, B] = extents(P, F, a, b);
  if (A.empty() || B.empty()) return reach;
  verify<NumericalError>(A.finite && B.finite, "body_gap: a particle's position or deformation gradient is not finite");
  // No centres closer than the boxes: no gap below reach unless the boxes come within R.
  const double R = reach + A.r() + B.r();
  double box_distance2 = 0.0;
  for (int k = 0; k < dim; ++k) {
    const double d = std::max({0.0, B.lo[k] - A.hi[k], A.lo[k] - B.hi[k]});
    box_distance2 += d * d;
  }
  if (box_distance2 >= R * R) return reach;

  const auto [a_near, b_near] = near_the_other(P, a, b, A, B, R);
  if (b_near.empty() || a_near.empty()) return reach;

  // The radius of particle p's deformed ball along the unit vector n, r0 |F_p^T n|, and a bound
  // of it along any n.
  auto radius = [&](std::size_t p, double r0, const Vec<dim>& n) {
    return F ? r0 * ((*F)[p].transpose() * n).norm() : r0;
  };
  auto largest_radius = [&](std::size_t p, double r0) { return F ? r0 * stretch_bound<dim>((*F)[p]) : r0; };

  // A's candidates by a lower bound of their gaps: the distance to B's box less their largest
  // radius and B's. Taken in that order, the search stops at the first whose bound reaches the
  // best gap.
  struct Candidate {
    double bound;
    std::size_t p;
  };
  std::vector<Candidate> order;
  order.reserve(a_near.size());
  for (const std::size_t p : a_near) {
    const Vec<dim> outside = (B.lo - P.x[p]).cwiseMax(P.x[p] - B.hi).cwiseMax(0.0);
    order.push_back({outside.norm() - largest_radius(p, half_width<dim>(P.volume0[p])) - B.r(), p});
  }
  std::sort(order.begin(), order.end(), [](const Candidate& c, const Candidate& d) { return c.bound < d.bound; });

  // B's candidates by cell (a counting sort, x fastest, so that a row of cells along x is one run
  // of entries). Cells as wide as B's smallest particle (an adaptive body's finest, along its
  // surface), or wider so that the table holds at most about eight cells per candidate.
  struct Entry {
    std::size_t q;
    double r0, largest;
  };
  std::vector<Entry> entries;
  entries.reserve(b_near.size());
  Extent<dim> box;
  double smallest = std::numeric_limits<double>::infinity();
  for (const std::size_t q : b_near) {
    const double r0 = half_width<dim>(P.volume0[q]);
    entries.push_back({q, r0, largest_radius(q, r0)});
    smallest = std::min(smallest, entries.back().largest);
    box.join({P.x[q], P.x[q], 0.0});
  }
  const Vec<dim> size = box.hi - box.lo;
  double h = 2.0 * smallest > 0.0 ? 2.0 * smallest : std::max(size.maxCoeff(), 1.0);  // points of no volume
  for (;; h *= 2.0) {  // wider cells until the table is small
    double total = 1.0;
    for (int k = 0; k < dim; ++k) total *= std::floor(size[k] / h) + 1.0;
    if (total <= 8.0 * b_near.size() + 1024.0) break;
  }
  IVec<dim> n;
  for (int k = 0; k < dim; ++k) n[k] = static_cast<int>(std::floor(size[k] / h)) + 1;
  auto cell_of = [&](const Vec<dim>& x) {
    IVec<dim> c;
    for (int k = 0; k < dim; ++k)  // clamped before the cast: a search box may reach far beyond the table
      c[k] = static_cast<int>(std::clamp(std::floor((x[k] - box.lo[k]) / h), -1.0, static_cast<double>(n[k])));
    return c;
  };
  auto key_of = [&](const IVec<dim>& c) {
    std::int64_t key = 0;
    for (int k = dim - 1; k >= 0; --k) key = key * n[k] + c[k];
    return static_cast<std::size_t>(key);
  };
  std::vector<std::size_t> start(static_cast<std::size_t>(n.template cast<std::int64_t>().prod()) + 1, 0);
  for (const Entry& e : entries) ++start[key_of(cell_of(P.x[e.q])) + 1];
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  std::vector<Entry> cells(entries.size());
  {
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (const Entry& e : entries) cells[next[key_of(cell_of(P.x[e.q]))]++] = e;
  }

  // The pairs of p closer than `best`: q within best + r_p + r_q of x_p, so in the cells within
  // best + r_p + B's largest radius, row by row.
  auto closest = [&](std::size_t p, double best) {
    const double r0p = half_width<dim>(P.volume0[p]), rp = largest_radius(p, r0p);
    const Vec<dim> x = P.x[p];
    const double search = best + rp + B.r();
    const IVec<dim> lo = cell_of(x - Vec<dim>::Constant(search)).cwiseMax(0);
    const IVec<dim> hi = cell_of(x + Vec<dim>::Constant(search)).cwiseMin(n - IVec<dim>::Ones());
    if ((lo.array() > hi.array()).any()) return best;
    const std::size_t row_length = static_cast<std::size_t>(hi[0] - lo[0]);
    IVec<dim> row_hi = hi;
    row_hi[0] = lo[0];
    for_each_in_box<dim>(lo, row_hi, [&](const IVec<dim>& c) {
      const std::size_t key = key_of(c);
      for (std::size_t i = start[key]; i < start[key + row_length + 1]; ++i) {
        const Entry& e = cells[i];
        const Vec<dim> d = P.x[e.q] - x;
        const double bound = best + rp + e.largest;
        if (d.squaredNorm() >= bound * bound) continue;
        const double distance = d.norm();
        const Vec<dim> unit = distance > 0.0 ? Vec<dim>(d / distance) : Vec<dim>(Vec<dim>::Unit(0));
        best = std::min(best, distance - radius(p, r0p, unit) - radius(e.q, e.r0, unit));
      }
    });
    return best;
  };
  // Blocks of candidates in parallel, each block searching within the best gap of those before.
  constexpr std::size_t kBlock = 4096;
  double best = reach;
  for (std::size_t first = 0; first < order.size() && order[first].bound < best; first += kBlock) {
    best = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(first, std::min(first + kBlock, order.size()), 64), best,
        [&](const tbb::blocked_range<std::size_t>& range, double local) {
          for (std::size_t i = range.begin(); i < range.end() && order[i].bound < local; ++i)
            local = closest(order[i].p, local);
          return local;
        },
        [](double x, double y) { return std::min(x, y); });
  }
  return best;
}

template double body_gap(const Particles<2>&, std::uint16_t, std::uint16_t, double, const std::vector<Mat<2>>*);
template double body_gap(const Particles<3>&, std::uint16_t, std::uint16_t, double, const std::vector<Mat<3>>*);

}  // namespace mpm::geometry
