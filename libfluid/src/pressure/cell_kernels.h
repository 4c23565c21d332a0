#pragma once
//! Private: the matrix-free product with A of CellOperator in gather form (each output written
//! by one task, so it runs under tbb::parallel_for without atomics), with a caller-owned
//! scratch for the nodal gradient so that iterative solvers do not reallocate it. The product
//! hands every cell's (A x)_c to an output functor, so that a Jacobi sweep or a residual is
//! fused into the same pass over memory (the multigrid smoother is bandwidth-bound).
//! NodeCell: pass 1 forms u_n = beta_n P_n (D^T x)_n on every node from its 2^dim surrounding
//! cells, pass 2 forms (A x)_c = -(D u)_c from the 2^dim corners of each fluid cell.
//! Poisson: the 2*dim+1-point stencil with p = 0 outside the box and in empty cells.
//! Operators with a periodic axis take separate loops that wrap every index (apply_*_periodic),
//! so that the loops of the other operators keep their precomputed offsets.
#include <fluid/pressure/cell_operator.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cstdint>
#include <vector>

namespace fluid::detail {

//! Index i of an axis of n points: wrapped into [0, n) when periodic, else i when in [0, n)
//! and -1 outside.
inline int wrap(int i, int n, bool periodic) {
  if (periodic) return ((i % n) + n) % n;
  return i >= 0 && i < n ? i : -1;
}

//! Whether a box of cells can halve for a multigrid coarse level: some axis has more than one
//! cell, and every periodic axis an even count >= 4 (the wrap must pair fine cells 2j, 2j + 1
//! into coarse cell j, and two coarse cells keep a two-colour smoother valid).
template <int dim>
bool can_halve(const IVec<dim>& cells, const std::array<bool, dim>& periodic) {
  bool ok = (cells.array() > 1).any();
  for (int a = 0; a < dim; ++a) ok = ok && (!periodic[a] || (cells[a] % 2 == 0 && cells[a] >= 4));
  return ok;
}

//! Calls fn(line coordinates, first index) for every x-line of the box `extent` (the
//! coordinates have x = 0), in parallel over lines; fn loops over x itself so that the inner
//! loop is a plain stride-1 loop.
template <int dim, class Fn>
void parallel_for_lines(const IVec<dim>& extent, Fn&& fn) {
  const std::int64_t lines = extent.template cast<std::int64_t>().prod() / extent[0];
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, lines, 16), [&](const tbb::blocked_range<std::int64_t>& r) {
    for (std::int64_t line = r.begin(); line < r.end(); ++line) {
      IVec<dim> q = IVec<dim>::Zero();
      std::int64_t rest = line;
      for (int a = 1; a < dim; ++a) {
        q[a] = static_cast<int>(rest % extent[a]);
        rest /= extent[a];
      }
      fn(q, line * extent[0]);
    }
  });
}

template <int dim, class Out>
void apply_poisson(const CellOperator<dim>& op, const std::vector<double>& x, Out&& out) {
  const double h2 = 1.0 / (op.dx * op.dx);
  const int nx = op.cells[0];
  std::array<std::int64_t, dim> stride{};
  stride[0] = 1;
  for (int a = 1; a < dim; ++a) stride[a] = stride[a - 1] * op.cells[a - 1];
  const CellType* type = op.type.data();
  parallel_for_lines<dim>(op.cells, [&](const IVec<dim>& c, std::int64_t base) {
    std::array<bool, dim> lower{}, upper{};
    for (int a = 1; a < dim; ++a) {
      lower[a] = c[a] > 0;
      upper[a] = c[a] + 1 < op.cells[a];
    }
    for (int i = 0; i < nx; ++i) {
      const std::int64_t ci = base + i;
      if (type[ci] != CellType::fluid) {
        out(ci, 0.0);
        continue;
      }
      double sum = 2.0 * dim * x[ci];
      if (i > 0 && type[ci - 1] == CellType::fluid) sum -= x[ci - 1];
      if (i + 1 < nx && type[ci + 1] == CellType::fluid) sum -= x[ci + 1];
      for (int a = 1; a < dim; ++a) {
        if (lower[a] && type[ci - stride[a]] == CellType::fluid) sum -= x[ci - stride[a]];
        if (upper[a] && type[ci + stride[a]] == CellType::fluid) sum -= x[ci + stride[a]];
      }
      out(ci, h2 * sum);
    }
  });
}

template <int dim, class Out>
void apply_node_cell(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& u, Out&& out) {
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
  // Corner k of a cell: node = cell + bits(k); seen from the node, the cell is node - bits(k).
  std::array<std::int64_t, corners> cell_offset{}, node_offset{};
  for (int k = 0; k < corners; ++k)
    for (int a = 0; a < dim; ++a)
      if ((k >> a) & 1) {
        cell_offset[k] -= cstride[a];
        node_offset[k] += nstride[a];
      }
  const CellType* type = op.type.data();
  const double* beta = op.beta.data();
  const std::int32_t* slip = op.has_slip() ? op.slip_index.data() : nullptr;
  // Pass 1: u_n = beta_n P_n (D^T x)_n, stored axis-major (u[a * node_count + n]).
  parallel_for_lines<dim>(nodes, [&](const IVec<dim>& n, std::int64_t node_base) {
    // Corners whose cell is inside the box along axes 1.. (the x test is per node below).
    std::array<bool, corners> line_inside{};
    std::int64_t cell_base = 0;  // index of the cell with the coordinates of node (0, n_1, ...)
    for (int a = 1; a < dim; ++a) cell_base += n[a] * cstride[a];
    for (int k = 0; k < corners; ++k) {
      line_inside[k] = true;
      for (int a = 1; a < dim; ++a) {
        const int c = n[a] - ((k >> a) & 1);
        line_inside[k] = line_inside[k] && c >= 0 && c < op.cells[a];
      }
    }
    for (int i = 0; i < nodes[0]; ++i) {
      const std::int64_t ni = node_base + i;
      Vec<dim> g = Vec<dim>::Zero();
      if (beta[ni] != 0.0) {
        for (int k = 0; k < corners; ++k) {
          const int cx = i - (k & 1);
          if (!line_inside[k] || cx < 0 || cx >= op.cells[0]) continue;
          const std::int64_t ci = cell_base + i + cell_offset[k];
          if (type[ci] != CellType::fluid) continue;
          for (int a = 0; a < dim; ++a) g[a] += ((k >> a) & 1) ? x[ci] : -x[ci];
        }
        g *= scale * beta[ni];
        if (slip && slip[ni] >= 0) g = op.slip_projector[static_cast<std::size_t>(slip[ni])] * g;
      }
      for (int a = 0; a < dim; ++a) u[a * node_count + ni] = g[a];
    }
  });
  // Pass 2: y_c = scale sum_k sum_a s_{k,a} u_a(corner k) for fluid cells.
  parallel_for_lines<dim>(op.cells, [&](const IVec<dim>& c, std::int64_t cell_base) {
    std::int64_t node_base = 0;
    for (int a = 1; a < dim; ++a) node_base += c[a] * nstride[a];
    for (int i = 0; i < op.cells[0]; ++i) {
      const std::int64_t ci = cell_base + i;
      if (type[ci] != CellType::fluid) {
        out(ci, 0.0);
        continue;
      }
      double sum = 0.0;
      for (int k = 0; k < corners; ++k) {
        const std::int64_t ni = node_base + i + node_offset[k];
        for (int a = 0; a < dim; ++a) sum += ((k >> a) & 1) ? u[a * node_count + ni] : -u[a * node_count + ni];
      }
      out(ci, scale * sum);
    }
  });
}

//! Index of the point q + d of a box with `extent` points per axis and x-stride 1, wrapped on
//! periodic axes; -1 outside a non-periodic axis.
template <int dim>
std::int64_t shifted_index(const IVec<dim>& q, const IVec<dim>& d, const IVec<dim>& extent,
                           const std::array<bool, dim>& periodic) {
  std::int64_t i = 0;
  for (int a = dim - 1; a >= 0; --a) {
    const int j = wrap(q[a] + d[a], extent[a], periodic[a]);
    if (j < 0) return -1;
    i = i * extent[a] + j;
  }
  return i;
}

template <int dim, class Out>
void apply_poisson_periodic(const CellOperator<dim>& op, const std::vector<double>& x, Out&& out) {
  const double h2 = 1.0 / (op.dx * op.dx);
  const CellType* type = op.type.data();
  parallel_for_lines<dim>(op.cells, [&](IVec<dim> c, std::int64_t base) {
    for (c[0] = 0; c[0] < op.cells[0]; ++c[0]) {
      const std::int64_t ci = base + c[0];
      if (type[ci] != CellType::fluid) {
        out(ci, 0.0);
        continue;
      }
      double sum = 2.0 * dim * x[ci];
      for (int a = 0; a < dim; ++a)
        for (int side : {-1, 1}) {
          const std::int64_t nb = shifted_index<dim>(c, side * IVec<dim>::Unit(a), op.cells, op.periodic);
          if (nb >= 0 && type[nb] == CellType::fluid) sum -= x[nb];
        }
      out(ci, h2 * sum);
    }
  });
}

//! Per axis, the wrapped neighbour index of point j of a box shifted by -bit (from_node: the
//! cell j - bit of node j, -1 outside) or +bit (from_cell: the node j + bit of cell j), stored
//! at [2 j + bit], so that the periodic loops below look up instead of dividing.
template <int dim>
struct WrapTables {
  std::array<std::vector<int>, dim> cell_of_node, node_of_cell;
  explicit WrapTables(const CellOperator<dim>& op) {
    const IVec<dim> nodes = op.node_extent();
    for (int a = 0; a < dim; ++a) {
      cell_of_node[a].resize(2 * static_cast<std::size_t>(nodes[a]));
      node_of_cell[a].resize(2 * static_cast<std::size_t>(op.cells[a]));
      for (int j = 0; j < nodes[a]; ++j)
        for (int bit = 0; bit < 2; ++bit) cell_of_node[a][2 * j + bit] = wrap(j - bit, op.cells[a], op.periodic[a]);
      for (int j = 0; j < op.cells[a]; ++j)
        for (int bit = 0; bit < 2; ++bit) node_of_cell[a][2 * j + bit] = wrap(j + bit, nodes[a], op.periodic[a]);
    }
  }
};

template <int dim, class Out>
void apply_node_cell_periodic(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& u,
                              Out&& out) {
  constexpr int corners = 1 << dim;
  const double scale = 1.0 / ((1 << (dim - 1)) * op.dx);
  const IVec<dim> nodes = op.node_extent();
  const std::int64_t node_count = op.node_count();
  u.resize(static_cast<std::size_t>(dim * node_count));
  const WrapTables<dim> tables(op);
  std::array<std::int64_t, dim> cstride{}, nstride{};
  cstride[0] = nstride[0] = 1;
  for (int a = 1; a < dim; ++a) {
    cstride[a] = cstride[a - 1] * op.cells[a - 1];
    nstride[a] = nstride[a - 1] * nodes[a - 1];
  }
  const CellType* type = op.type.data();
  const double* beta = op.beta.data();
  const std::int32_t* slip = op.has_slip() ? op.slip_index.data() : nullptr;
  // Pass 1: u_n = beta_n P_n (D^T x)_n from the cells n - bits(k) (corner k of each).
  parallel_for_lines<dim>(nodes, [&](const IVec<dim>& n, std::int64_t node_base) {
    std::array<std::int64_t, corners> line{};  // cell index of axes 1.. for corner k, -1 outside
    for (int k = 0; k < corners; ++k)
      for (int a = 1; a < dim && line[k] >= 0; ++a) {
        const int c = tables.cell_of_node[a][2 * n[a] + ((k >> a) & 1)];
        line[k] = c < 0 ? -1 : line[k] + c * cstride[a];
      }
    for (int i = 0; i < nodes[0]; ++i) {
      const std::int64_t ni = node_base + i;
      Vec<dim> g = Vec<dim>::Zero();
      if (beta[ni] != 0.0) {
        for (int k = 0; k < corners; ++k) {
          const int cx = tables.cell_of_node[0][2 * i + (k & 1)];
          if (line[k] < 0 || cx < 0) continue;
          const std::int64_t ci = line[k] + cx;
          if (type[ci] != CellType::fluid) continue;
          for (int a = 0; a < dim; ++a) g[a] += ((k >> a) & 1) ? x[ci] : -x[ci];
        }
        g *= scale * beta[ni];
        if (slip && slip[ni] >= 0) g = op.slip_projector[static_cast<std::size_t>(slip[ni])] * g;
      }
      for (int a = 0; a < dim; ++a) u[a * node_count + ni] = g[a];
    }
  });
  // Pass 2: y_c = scale sum_k sum_a s_{k,a} u_a(corner k) for fluid cells.
  parallel_for_lines<dim>(op.cells, [&](const IVec<dim>& c, std::int64_t cell_base) {
    std::array<std::int64_t, corners> line{};  // node index of axes 1.. for corner k
    for (int k = 0; k < corners; ++k)
      for (int a = 1; a < dim; ++a) line[k] += tables.node_of_cell[a][2 * c[a] + ((k >> a) & 1)] * nstride[a];
    for (int i = 0; i < op.cells[0]; ++i) {
      const std::int64_t ci = cell_base + i;
      if (type[ci] != CellType::fluid) {
        out(ci, 0.0);
        continue;
      }
      double sum = 0.0;
      for (int k = 0; k < corners; ++k) {
        const std::int64_t ni = line[k] + tables.node_of_cell[0][2 * i + (k & 1)];
        for (int a = 0; a < dim; ++a) sum += ((k >> a) & 1) ? u[a * node_count + ni] : -u[a * node_count + ni];
      }
      out(ci, scale * sum);
    }
  });
}

//! Calls out(c, (A x)_c) once for every cell c (0 for empty cells); `node_scratch` is resized
//! as needed (NodeCell only).
template <int dim, class Out>
void apply_operator_to(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& node_scratch,
                       Out&& out) {
  const bool poisson = op.kind == CellOperator<dim>::Kind::poisson;
  if (op.is_periodic()) {
    if (poisson)
      apply_poisson_periodic<dim>(op, x, out);
    else
      apply_node_cell_periodic<dim>(op, x, node_scratch, out);
  } else if (poisson) {
    apply_poisson<dim>(op, x, out);
  } else {
    apply_node_cell<dim>(op, x, node_scratch, out);
  }
}

//! y = A x (same semantics as CellOperator::apply).
template <int dim>
void apply_operator(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& y,
                    std::vector<double>& node_scratch) {
  y.resize(static_cast<std::size_t>(op.cell_count()));
  apply_operator_to<dim>(op, x, node_scratch, [&y](std::int64_t c, double v) { y[c] = v; });
}

}  // namespace fluid::detail
