// Gather-form kernels of the pressure operator (definitions in cell_operator.h).
// NodeCell: pass 1 forms u_n = beta_n (D^T x)_n on every node from its 2^dim surrounding cells,
// pass 2 forms y_c = -(D u)_c from the 2^dim corners of each fluid cell. Poisson: the
// 2*dim+1-point stencil with p = 0 outside the box and in empty cells.
#include "cell_kernels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cstdint>

namespace fluid::detail {

namespace {

//! Calls fn(coordinates, linear index) for every point of the box `extent` whose last
//! coordinate lies in [lo, hi), x fastest; parallel over the last axis.
template <int dim, class Fn>
void parallel_for_box(const IVec<dim>& extent, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<int>(0, extent[dim - 1]), [&](const tbb::blocked_range<int>& r) {
    IVec<dim> q = IVec<dim>::Zero();
    q[dim - 1] = r.begin();
    std::int64_t stride = 1;
    for (int a = 0; a < dim - 1; ++a) stride *= extent[a];
    const std::int64_t begin = stride * r.begin(), end = stride * r.end();
    for (std::int64_t index = begin; index < end; ++index) {
      fn(q, index);
      for (int a = 0; a < dim; ++a) {
        if (++q[a] < extent[a]) break;
        q[a] = 0;
      }
    }
  });
}

template <int dim>
void apply_poisson(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& y) {
  const double h2 = 1.0 / (op.dx * op.dx);
  std::array<std::int64_t, dim> stride{};
  stride[0] = 1;
  for (int a = 1; a < dim; ++a) stride[a] = stride[a - 1] * op.cells[a - 1];
  parallel_for_box<dim>(op.cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (op.type[ci] != CellType::fluid) {
      y[ci] = 0.0;
      return;
    }
    double sum = 2.0 * dim * x[ci];
    for (int a = 0; a < dim; ++a) {
      if (c[a] > 0 && op.type[ci - stride[a]] == CellType::fluid) sum -= x[ci - stride[a]];
      if (c[a] + 1 < op.cells[a] && op.type[ci + stride[a]] == CellType::fluid) sum -= x[ci + stride[a]];
    }
    y[ci] = h2 * sum;
  });
}

template <int dim>
void apply_node_cell(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& y,
                     std::vector<double>& u) {
  constexpr int corners = 1 << dim;
  const double scale = 1.0 / ((1 << (dim - 1)) * op.dx);
  const IVec<dim> nodes = op.cells.array() + 1;
  const std::int64_t node_count = op.node_count();
  u.resize(static_cast<std::size_t>(dim * node_count));
  std::array<std::int64_t, dim> cstride{}, nstride{};
  cstride[0] = nstride[0] = 1;
  for (int a = 1; a < dim; ++a) {
    cstride[a] = cstride[a - 1] * op.cells[a - 1];
    nstride[a] = nstride[a - 1] * nodes[a - 1];
  }
  // Corner k of a cell: node = cell + bits(k); as seen from the node, the cell is node - bits(k).
  std::array<std::int64_t, corners> cell_offset{}, node_offset{};
  for (int k = 0; k < corners; ++k)
    for (int a = 0; a < dim; ++a)
      if ((k >> a) & 1) {
        cell_offset[k] -= cstride[a];
        node_offset[k] += nstride[a];
      }
  // Pass 1: u_n = beta_n (D^T x)_n, stored axis-major (u[a * node_count + n]).
  parallel_for_box<dim>(nodes, [&](const IVec<dim>& n, std::int64_t ni) {
    Vec<dim> g = Vec<dim>::Zero();
    if (op.beta[ni] != 0.0) {
      std::int64_t base = 0;  // index of cell n (may be out of range; only valid corners are read)
      for (int a = 0; a < dim; ++a) base += n[a] * cstride[a];
      for (int k = 0; k < corners; ++k) {
        bool inside = true;
        for (int a = 0; a < dim; ++a) {
          const int c = n[a] - ((k >> a) & 1);
          inside = inside && c >= 0 && c < op.cells[a];
        }
        if (!inside) continue;
        const std::int64_t ci = base + cell_offset[k];
        if (op.type[ci] != CellType::fluid) continue;
        for (int a = 0; a < dim; ++a) g[a] += ((k >> a) & 1) ? x[ci] : -x[ci];
      }
      g *= scale * op.beta[ni];
    }
    for (int a = 0; a < dim; ++a) u[a * node_count + ni] = g[a];
  });
  // Pass 2: y_c = scale sum_k sum_a s_{k,a} u_a(corner k) for fluid cells.
  parallel_for_box<dim>(op.cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (op.type[ci] != CellType::fluid) {
      y[ci] = 0.0;
      return;
    }
    std::int64_t base = 0;
    for (int a = 0; a < dim; ++a) base += c[a] * nstride[a];
    double sum = 0.0;
    for (int k = 0; k < corners; ++k) {
      const std::int64_t ni = base + node_offset[k];
      for (int a = 0; a < dim; ++a) sum += ((k >> a) & 1) ? u[a * node_count + ni] : -u[a * node_count + ni];
    }
    y[ci] = scale * sum;
  });
}

}  // namespace

template <int dim>
void apply_operator(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& y,
                    std::vector<double>& node_scratch) {
  y.resize(static_cast<std::size_t>(op.cell_count()));
  if (op.kind == CellOperator<dim>::Kind::poisson)
    apply_poisson<dim>(op, x, y);
  else
    apply_node_cell<dim>(op, x, y, node_scratch);
}

template void apply_operator<2>(const CellOperator<2>&, const std::vector<double>&, std::vector<double>&,
                                std::vector<double>&);
template void apply_operator<3>(const CellOperator<3>&, const std::vector<double>&, std::vector<double>&,
                                std::vector<double>&);

}  // namespace fluid::detail
