// The node/cell operator A = D B D^T of the semi-staggered projection and the standard
// cell-centred Laplacian (see cell_operator.h for the definitions). For a multilinear nodal
// field the cell average of d u_a / d x_a is the difference of the averages of u_a over the
// two faces normal to a, i.e. sum over the 2^dim corners of s_a u_a / (2^{dim-1} dx).
#include <fluid/pressure/cell_operator.h>

#include "cell_kernels.h"

#include <mpm/core/error.h>

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

template <int dim, class Fn>
void for_each_cell(const IVec<dim>& cells, Fn&& fn) {
  IVec<dim> c = IVec<dim>::Zero();
  const std::int64_t n = cells.template cast<std::int64_t>().prod();
  for (std::int64_t index = 0; index < n; ++index) {
    fn(c, index);
    for (int a = 0; a < dim; ++a) {
      if (++c[a] < cells[a]) break;
      c[a] = 0;
    }
  }
}
}  // namespace

template <int dim>
std::int64_t CellOperator<dim>::cell_count() const { return cells.template cast<std::int64_t>().prod(); }

template <int dim>
std::int64_t CellOperator<dim>::node_count() const {
  return (cells.array() + 1).template cast<std::int64_t>().prod();
}

template <int dim>
std::int64_t CellOperator<dim>::cell_index(const IVec<dim>& c) const {
  std::int64_t i = 0;
  for (int a = dim - 1; a >= 0; --a) i = i * cells[a] + c[a];
  return i;
}

template <int dim>
std::int64_t CellOperator<dim>::node_index(const IVec<dim>& n) const {
  std::int64_t i = 0;
  for (int a = dim - 1; a >= 0; --a) i = i * (cells[a] + 1) + n[a];
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
  for (std::size_t i = 0; i < grad.size(); ++i) u[i] += beta[i] * grad[i];
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
void CellOperator<dim>::diagonal(std::vector<double>& d) const {
  d.assign(static_cast<std::size_t>(cell_count()), 0.0);
  const double s2 = 1.0 / ((1 << (2 * dim - 2)) * dx * dx);
  for_each_cell<dim>(cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (type[ci] != CellType::fluid) return;
    if (kind == Kind::poisson) {
      d[ci] = 2.0 * dim / (dx * dx);
      return;
    }
    for (int k = 0; k < corners<dim>; ++k) d[ci] += dim * s2 * beta[node_index(corner_node<dim>(c, k))];
  });
}

template <int dim>
void CellOperator<dim>::for_each_entry(const std::function<void(std::int64_t, std::int64_t, double)>& f) const {
  const double s2 = 1.0 / ((1 << (2 * dim - 2)) * dx * dx);
  for_each_cell<dim>(cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (type[ci] != CellType::fluid) return;
    // Neighbours c + o, o in {-1, 0, 1}^dim, visited in ascending cell index (x fastest).
    IVec<dim> o = IVec<dim>::Constant(-1);
    for (int m = 0; m < mpm::ipow(3, dim); ++m) {
      const IVec<dim> nb = c + o;
      const bool inside = (nb.array() >= 0).all() && (nb.array() < cells.array()).all();
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
            double dot = 0.0;
            for (int a = 0; a < dim; ++a) dot += (bits[a] ? 1.0 : -1.0) * (nb_bits[a] ? 1.0 : -1.0);
            v += s2 * beta[node_index(c + bits)] * dot;
          }
        }
        if (v != 0.0) f(ci, cell_index(nb), v);
      }
      for (int a = 0; a < dim; ++a) {
        if (++o[a] <= 1) break;
        o[a] = -1;
      }
    }
  });
}

template struct CellOperator<2>;
template struct CellOperator<3>;

}  // namespace fluid
