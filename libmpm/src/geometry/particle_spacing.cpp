// Particle spacing (particle_spacing.h) on a dense box of cells around the particles, padded by
// two cells so that the dilation of a cell at the edge stays in the box.
#include <mpm/geometry/particle_spacing.h>

#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace mpm::geometry {

namespace {
//! Calls f(cell, index) for every cell of a box with n cells per axis, x fastest.
template <int dim, class Fn>
void for_each_cell(const IVec<dim>& n, Fn&& f) {
  std::int64_t i = 0;
  for_each_in_box<dim>(IVec<dim>::Zero(), n - IVec<dim>::Ones(), [&](const IVec<dim>& c) { f(c, i++); });
}

//! out_c = 1 iff (any / every) cell of the 3^dim box around c has in = 1 (outside the box: 0).
template <int dim>
std::vector<std::uint8_t> box_filter(const std::vector<std::uint8_t>& in, const IVec<dim>& n, bool any) {
  std::vector<std::uint8_t> out(in.size(), 0);
  for_each_cell<dim>(n, [&](const IVec<dim>& c, std::int64_t i) {
    bool hit = !any;
    IVec<dim> o = IVec<dim>::Constant(-1);
    for (int m = 0; m < ipow(3, dim); ++m) {
      const IVec<dim> d = c + o;
      bool set = false;
      if ((d.array() >= 0).all() && (d.array() < n.array()).all()) {
        std::int64_t j = 0;
        for (int a = dim - 1; a >= 0; --a) j = j * n[a] + d[a];
        set = in[static_cast<std::size_t>(j)] != 0;
      }
      hit = any ? (hit || set) : (hit && set);
      for (int a = 0; a < dim; ++a) {
        if (++o[a] <= 1) break;
        o[a] = -1;
      }
    }
    out[static_cast<std::size_t>(i)] = hit;
  });
  return out;
}
}  // namespace

template <int dim>
ParticleSpacing particle_spacing(const std::vector<Vec<dim>>& x, const Vec<dim>& origin, double dx,
                                 const std::vector<Vec<dim>>& excluding) {
  verify<InputError>(dx > 0.0, "particle_spacing: the cell size must be positive");
  ParticleSpacing result;
  if (x.empty()) return result;
  for (const Vec<dim>& p : x)
    verify<NumericalError>(p.allFinite(), "particle_spacing: a particle position is not finite");
  auto cell = [&](const Vec<dim>& p) {
    IVec<dim> c;
    for (int a = 0; a < dim; ++a) c[a] = static_cast<int>(std::floor((p[a] - origin[a]) / dx));
    return c;
  };
  IVec<dim> lo = cell(x[0]), hi = lo;
  for (const Vec<dim>& p : x) {
    lo = lo.cwiseMin(cell(p));
    hi = hi.cwiseMax(cell(p));
  }
  lo -= IVec<dim>::Constant(2);
  const IVec<dim> n = hi - lo + IVec<dim>::Constant(3);
  // The dense box of cells: a few bytes per cell, bounded so that a body spread over a huge
  // domain is refused rather than allocated.
  verify<InputError>(n.template cast<double>().prod() <= 1e9,
                     "particle_spacing: the particles span more than 1e9 cells of size " + std::to_string(dx) + " m");
  // Box index of the cell holding p, or -1 outside the box.
  auto index_of = [&](const Vec<dim>& p) -> std::int64_t {
    const IVec<dim> c = cell(p) - lo;
    if ((c.array() < 0).any() || (c.array() >= n.array()).any()) return -1;
    std::int64_t j = 0;
    for (int a = dim - 1; a >= 0; --a) j = j * n[a] + c[a];
    return j;
  };
  std::vector<std::int64_t> count(static_cast<std::size_t>(n.template cast<std::int64_t>().prod()), 0);
  for (const Vec<dim>& p : x) ++count[static_cast<std::size_t>(index_of(p))];
  std::vector<std::uint8_t> occupied(count.size());
  std::transform(count.begin(), count.end(), occupied.begin(), [](std::int64_t k) { return k > 0; });
  std::vector<std::uint8_t> inside =
      box_filter<dim>(box_filter<dim>(box_filter<dim>(occupied, n, true), n, false), n, false);
  for (const Vec<dim>& p : excluding) {
    if (!p.allFinite()) continue;
    if (const std::int64_t j = index_of(p); j >= 0) inside[static_cast<std::size_t>(j)] = 0;
  }

  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < count.size(); ++i)
    if (inside[i]) {
      ++result.inside_cells;
      sum += static_cast<double>(count[i]);
      sum2 += static_cast<double>(count[i]) * static_cast<double>(count[i]);
    }
  if (result.inside_cells == 0) return result;
  const auto cells = static_cast<double>(result.inside_cells);
  result.mean_count = sum / cells;
  result.count_cv = std::sqrt(std::max(0.0, sum2 / cells - result.mean_count * result.mean_count)) / result.mean_count;
  std::int64_t empty = 0, sparse = 0;
  for (std::size_t i = 0; i < count.size(); ++i)
    if (inside[i]) {
      empty += count[i] == 0;
      sparse += static_cast<double>(count[i]) <= 0.25 * result.mean_count;
    }
  result.empty_share = static_cast<double>(empty) / cells;
  result.sparse_share = static_cast<double>(sparse) / cells;
  return result;
}

template ParticleSpacing particle_spacing(const std::vector<Vec<2>>&, const Vec<2>&, double,
                                          const std::vector<Vec<2>>&);
template ParticleSpacing particle_spacing(const std::vector<Vec<3>>&, const Vec<3>&, double,
                                          const std::vector<Vec<3>>&);

}  // namespace mpm::geometry
