// The node/cell operator A = D B D^T of the semi-staggered projection and the standard
// cell-centred Laplacian (see cell_operator.h for the definitions). For a multilinear nodal
// field the cell average of d u_a / d x_a is the difference of the averages of u_a over the
// two faces normal to a, i.e. sum over the 2^dim corners of s_a u_a / (2^{dim-1} dx).
#include <fluid/pressure/cell_operator.h>

#include "cell_kernels.h"

#include <mpm/core/error.h>

#include <algorithm>
#include <utility>

namespace fluid {

namespace {
template <int dim>
constexpr int corners = 1 << dim;

//! Corner k of cell c: node c + bits of k; sign of axis a is + for the upper corner.
template <int dim>
IVec<dim> corner_node(const IVec<dim>& c, int k) {
  IVec<dim> n = c;
  for (int a = 0; a < dim; ++a) n[a] += (k >> a) & 1;
  return n;
}
inline double corner_sign(int k, int a) { return ((k >> a) & 1) ? 1.0 : -1.0; }
//! (corner_sign(k, a))_a: the direction of corner k from the cell centre, scaled to +-1.
template <int dim>
Vec<dim> corner_signs(int k) {
  Vec<dim> s;
  for (int a = 0; a < dim; ++a) s[a] = corner_sign(k, a);
  return s;
}

template <int dim, class Fn>
void for_each_cell(const IVec<dim>& cells, Fn&& fn) {
  std::int64_t index = 0;
  mpm::for_each_in_box<dim>(IVec<dim>::Zero(), cells - IVec<dim>::Ones(), [&](const IVec<dim>& c) { fn(c, index++); });
}
}  // namespace

template <int dim>
std::int64_t CellOperator<dim>::cell_count() const {
  return cells.template cast<std::int64_t>().prod();
}

template <int dim>
bool CellOperator<dim>::is_periodic() const {
  return std::any_of(periodic.begin(), periodic.end(), [](bool p) { return p; });
}

template <int dim>
IVec<dim> CellOperator<dim>::node_extent() const {
  IVec<dim> n = cells;
  for (int a = 0; a < dim; ++a) n[a] += periodic[a] ? 0 : 1;
  return n;
}

template <int dim>
std::int64_t CellOperator<dim>::node_count() const {
  return node_extent().template cast<std::int64_t>().prod();
}

template <int dim>
std::int64_t CellOperator<dim>::cell_index(const IVec<dim>& c) const {
  std::int64_t i = 0;
  for (int a = dim - 1; a >= 0; --a) i = i * cells[a] + c[a];
  return i;
}

template <int dim>
std::int64_t CellOperator<dim>::node_index(IVec<dim> n) const {
  const IVec<dim> extent = node_extent();
  std::int64_t i = 0;
  for (int a = dim - 1; a >= 0; --a) i = i * extent[a] + detail::wrap(n[a], extent[a], periodic[a]);
  return i;
}

template <int dim>
void CellOperator<dim>::subtract_gradient(const std::vector<double>& p, std::vector<Vec<dim>>& u) const {
  const double scale = 1.0 / ((1 << (dim - 1)) * dx);
  std::vector<Vec<dim>> grad(static_cast<std::size_t>(node_count()), Vec<dim>::Zero());
  for_each_cell<dim>(cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (type[ci] != CellType::fluid || p[ci] == 0.0) return;
    for (int k = 0; k < corners<dim>; ++k) {
      Vec<dim>& g = grad[node_index(corner_node<dim>(c, k))];
      for (int a = 0; a < dim; ++a) g[a] += corner_sign(k, a) * scale * p[ci];
    }
  });
  for (std::size_t i = 0; i < grad.size(); ++i) u[i] += mobility(static_cast<std::int64_t>(i), grad[i]);
}

template <int dim>
void CellOperator<dim>::divergence(const std::vector<Vec<dim>>& u, std::vector<double>& div) const {
  const double scale = 1.0 / ((1 << (dim - 1)) * dx);
  div.assign(static_cast<std::size_t>(cell_count()), 0.0);
  for_each_cell<dim>(cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (type[ci] != CellType::fluid) return;
    double d = 0.0;
    for (int k = 0; k < corners<dim>; ++k) {
      const Vec<dim>& v = u[node_index(corner_node<dim>(c, k))];
      for (int a = 0; a < dim; ++a) d += corner_sign(k, a) * v[a];
    }
    div[ci] = -scale * d;
  });
}

template <int dim>
void CellOperator<dim>::apply(const std::vector<double>& x, std::vector<double>& y) const {
  std::vector<double> node_scratch;
  detail::apply_operator<dim>(*this, x, y, node_scratch);
}

template <int dim>
void CellOperator<dim>::set_slip(std::int64_t i, const Mat<dim>& free) {
  if (slip_index.empty()) slip_index.assign(static_cast<std::size_t>(node_count()), -1);
  slip_index[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(slip_projector.size());
  slip_projector.push_back(free);
}

template <int dim>
void CellOperator<dim>::clear_slip() {
  slip_index.clear();
  slip_projector.clear();
}

template <int dim>
void CellOperator<dim>::empty_cells_without_unknowns() {
  for_each_cell<dim>(cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (type[ci] != CellType::fluid) return;
    for (int k = 0; k < corners<dim>; ++k)
      if (beta[node_index(corner_node<dim>(c, k))] > 0.0) return;
    type[ci] = CellType::empty;
  });
}

template <int dim>
void CellOperator<dim>::diagonal(std::vector<double>& d) const {
  d.assign(static_cast<std::size_t>(cell_count()), 0.0);
  const double s2 = 1.0 / ((1 << (2 * dim - 2)) * dx * dx);
  for_each_cell<dim>(cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (type[ci] != CellType::fluid) return;
    if (kind == Kind::poisson) {
      // A periodic axis of one cell makes the cell its own neighbour on both sides.
      int self = 0;
      for (int a = 0; a < dim; ++a) self += periodic[a] && cells[a] == 1;
      d[ci] = 2.0 * (dim - self) / (dx * dx);
      return;
    }
    // sum over the corner pairs (k, k') at the same node of s_k . beta P s_k'; distinct
    // corners share a node only on a periodic axis of one cell.
    for (int k = 0; k < corners<dim>; ++k) {
      const std::int64_t n = node_index(corner_node<dim>(c, k));
      for (int k2 = 0; k2 < corners<dim>; ++k2) {
        if (k2 != k && node_index(corner_node<dim>(c, k2)) != n) continue;
        d[ci] += s2 * corner_signs<dim>(k).dot(mobility(n, corner_signs<dim>(k2)));
      }
    }
  });
}

template <int dim>
void CellOperator<dim>::for_each_entry(const std::function<void(std::int64_t, std::int64_t, double)>& f) const {
  for_each_entry(0, cell_count(), f);
}

template <int dim>
void CellOperator<dim>::for_each_entry(std::int64_t first, std::int64_t last,
                                       const std::function<void(std::int64_t, std::int64_t, double)>& f) const {
  const double s2 = 1.0 / ((1 << (2 * dim - 2)) * dx * dx);
  std::vector<std::pair<std::int64_t, double>> row;
  for (std::int64_t ci = first; ci < last; ++ci) {
    if (type[ci] != CellType::fluid) continue;
    IVec<dim> c;
    for (std::int64_t a = 0, rest = ci; a < dim; ++a) {
      c[a] = static_cast<int>(rest % cells[a]);
      rest /= cells[a];
    }
    // Neighbours c + o, o in {-1, 0, 1}^dim (wrapped on periodic axes, where several o may
    // name one cell: their values add), then sorted by cell index.
    row.clear();
    IVec<dim> o = IVec<dim>::Constant(-1);
    for (int m = 0; m < mpm::ipow(3, dim); ++m) {
      IVec<dim> nb = c + o;
      bool inside = true;
      for (int a = 0; a < dim; ++a) {
        nb[a] = detail::wrap(nb[a], cells[a], periodic[a]);
        inside = inside && nb[a] >= 0;
      }
      if (inside && type[cell_index(nb)] == CellType::fluid) {
        double v = 0.0;
        if (kind == Kind::poisson) {
          const int distance = o.cwiseAbs().sum();
          v = distance == 0 ? 2.0 * dim / (dx * dx) : distance == 1 ? -1.0 / (dx * dx) : 0.0;
        } else {
          // Shared corners: node n of c (corner k) is corner k' = k - o of nb when in range.
          for (int k = 0; k < corners<dim>; ++k) {
            IVec<dim> bits, nb_bits;
            bool shared = true;
            for (int a = 0; a < dim; ++a) {
              bits[a] = (k >> a) & 1;
              nb_bits[a] = bits[a] - o[a];
              shared = shared && nb_bits[a] >= 0 && nb_bits[a] <= 1;
            }
            if (!shared) continue;
            const Vec<dim> s = (2.0 * bits.template cast<double>().array() - 1.0).matrix();
            const Vec<dim> s_nb = (2.0 * nb_bits.template cast<double>().array() - 1.0).matrix();
            v += s2 * s.dot(mobility(node_index(c + bits), s_nb));
          }
        }
        if (v != 0.0) row.emplace_back(cell_index(nb), v);
      }
      for (int a = 0; a < dim; ++a) {
        if (++o[a] <= 1) break;
        o[a] = -1;
      }
    }
    std::sort(row.begin(), row.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (std::size_t e = 0; e < row.size();) {
      double v = 0.0;
      const std::int64_t column = row[e].first;
      for (; e < row.size() && row[e].first == column; ++e) v += row[e].second;
      if (v != 0.0) f(ci, column, v);
    }
  }
}

template struct CellOperator<2>;
template struct CellOperator<3>;

}  // namespace fluid
