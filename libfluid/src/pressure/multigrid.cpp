// Geometric multigrid V-cycle (definitions and choices in multigrid.h).
#include <fluid/pressure/multigrid.h>

#include "cell_kernels.h"

#include <mpm/core/error.h>
#include <mpm/core/solve/vector_space.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

namespace fluid {

namespace {

using mpm::solve::for_each_entry;

//! out = in, entry by entry in parallel (a fine level is tens of megabytes: a serial copy
//! would be the cycle's serial section).
void copy_entries(const std::vector<double>& in, std::vector<double>& out) {
  out.resize(in.size());
  for_each_entry(in.size(), [&](std::size_t i) { out[i] = in[i]; });
}

//! Per axis, the two coarse cells a fine cell interpolates from, with weights 3/4 and 1/4;
//! the 1/4 neighbour wraps on a periodic axis and is mirrored at a box face otherwise.
struct AxisWeights {
  std::array<int, 2> coarse;
  std::array<double, 2> weight;
};
inline AxisWeights axis_weights(int i, int coarse_cells, bool dirichlet, bool periodic) {
  const int near = i >> 1;
  const int far = detail::wrap(near + ((i & 1) ? 1 : -1), coarse_cells, periodic);
  if (far >= 0) return {{near, far}, {0.75, 0.25}};
  return {{near, near}, {0.75, dirichlet ? -0.25 : 0.25}};
}

//! One axis of the tensor-product transfer: prolongation (coarse -> fine along axis a, the
//! 1D interpolation) or its exact transpose (fine -> coarse). `in_extent` / `out_extent` are
//! the box sizes of in / out, which differ only along a.
template <int dim>
void transfer_axis(const std::vector<double>& in, const IVec<dim>& in_extent, std::vector<double>& out,
                   const IVec<dim>& out_extent, int a, bool prolong, bool dirichlet, bool periodic) {
  std::int64_t inner = 1, outer = 1;
  for (int d = 0; d < a; ++d) inner *= in_extent[d];
  for (int d = a + 1; d < dim; ++d) outer *= in_extent[d];
  const int n_in = in_extent[a], n_out = out_extent[a];
  const int n_fine = prolong ? n_out : n_in, n_coarse = prolong ? n_in : n_out;
  // Prolongation writes every entry of out; restriction adds into it.
  out.resize(static_cast<std::size_t>(out_extent.template cast<std::int64_t>().prod()));
  if (!prolong) for_each_entry(out.size(), [&](std::size_t k) { out[k] = 0.0; });
  // Tasks of (outer index, chunk of the inner range): each writes its own entries of out, for
  // every i in the same order, so the result does not depend on the threads. Chunks of the
  // inner range give the last axis (outer = 1) its parallelism.
  constexpr std::int64_t chunk = 2048;
  const std::int64_t chunks = (inner + chunk - 1) / chunk;
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, outer * chunks), [&](const auto& tasks) {
    for (std::int64_t task = tasks.begin(); task != tasks.end(); ++task) {
      const std::int64_t o = task / chunks, q0 = (task % chunks) * chunk, q1 = std::min(inner, q0 + chunk);
      for (int i = 0; i < n_fine; ++i) {
        const AxisWeights w = axis_weights(i, n_coarse, dirichlet, periodic);
        const std::int64_t fine = (o * n_fine + i) * inner;
        const std::int64_t near = (o * n_coarse + w.coarse[0]) * inner, far = (o * n_coarse + w.coarse[1]) * inner;
        if (prolong) {
          for (std::int64_t q = q0; q < q1; ++q) out[fine + q] = w.weight[0] * in[near + q] + w.weight[1] * in[far + q];
        } else {
          for (std::int64_t q = q0; q < q1; ++q) {
            out[near + q] += w.weight[0] * in[fine + q];
            out[far + q] += w.weight[1] * in[fine + q];
          }
        }
      }
    }
  });
}

template <int dim>
CellOperator<dim> coarsen(const CellOperator<dim>& fine) {
  CellOperator<dim> coarse;
  coarse.kind = fine.kind;
  coarse.periodic = fine.periodic;
  coarse.cells = (fine.cells.array() + 1) / 2;
  coarse.dx = 2.0 * fine.dx;
  coarse.type.assign(static_cast<std::size_t>(coarse.cell_count()), CellType::empty);
  IVec<dim> c = IVec<dim>::Zero();
  for (std::int64_t ci = 0; ci < fine.cell_count(); ++ci) {
    if (fine.type[ci] == CellType::fluid) coarse.type[coarse.cell_index(c.array() / 2)] = CellType::fluid;
    for (int a = 0; a < dim; ++a) {
      if (++c[a] < fine.cells[a]) break;
      c[a] = 0;
    }
  }
  if (fine.kind == CellOperator<dim>::Kind::node_cell) {
    coarse.beta.assign(static_cast<std::size_t>(coarse.node_count()), 0.0);
    const IVec<dim> extent = coarse.node_extent();
    IVec<dim> n = IVec<dim>::Zero();
    for (std::int64_t ni = 0; ni < coarse.node_count(); ++ni) {
      const IVec<dim> fine_node = (2 * n).cwiseMin(fine.cells);
      coarse.beta[ni] = fine.beta[fine.node_index(fine_node)];
      for (int a = 0; a < dim; ++a) {
        if (++n[a] < extent[a]) break;
        n[a] = 0;
      }
    }
  }
  return coarse;
}

}  // namespace

template <int dim>
bool Multigrid<dim>::supports(const CellOperator<dim>& op) {
  if (op.kind == CellOperator<dim>::Kind::poisson) return true;
  // 2D NodeCell: the column colouring needs an even count on a periodic x axis. A coarse
  // level with an odd periodic count cannot coarsen further, so it is the bottom (solved,
  // not smoothed): only the fine count decides.
  return dim == 2 && (!op.periodic[0] || op.cells[0] % 2 == 0);
}

template <int dim>
Multigrid<dim>::Multigrid(const CellOperator<dim>& fine, const Options& options) : fine_(fine), options_(options) {
  mpm::verify<mpm::InputError>(options.smoothing_sweeps >= 1, "Multigrid: smoothing_sweeps must be >= 1");
  mpm::verify<mpm::InputError>(supports(fine),
                               "Multigrid: no Gauss-Seidel smoother for this operator (3D NodeCell, "
                               "or 2D NodeCell with an odd periodic x count): use ModulatedMultigrid");
  for (int a = 0; a < dim; ++a)
    mpm::verify<mpm::InputError>(
        !fine.periodic[a] || fine.kind == CellOperator<dim>::Kind::node_cell || fine.cells[a] % 2 == 0,
        "Multigrid: the red-black smoother of a periodic Poisson operator needs an even "
        "cell count on every periodic axis");
  levels_.emplace_back();
  auto fluid_cells = [](const CellOperator<dim>& o) {
    return std::count(o.type.begin(), o.type.end(), CellType::fluid);
  };
  while (fluid_cells(op(level_count() - 1)) > options.max_coarse_cells &&
         detail::can_halve<dim>(op(level_count() - 1).cells, fine.periodic)) {
    Level next;
    next.op = coarsen(op(level_count() - 1));
    levels_.push_back(std::move(next));
  }
  for (int l = 0; l < level_count(); ++l) {
    Level& level = levels_[l];
    const auto n = static_cast<std::size_t>(op(l).cell_count());
    level.b.assign(n, 0.0);
    level.x.assign(n, 0.0);
    level.r.assign(n, 0.0);
  }
  if (dim == 2 && fine.kind == CellOperator<dim>::Kind::node_cell) {
    checkerboard_.resize(static_cast<std::size_t>(fine.cell_count()));
    IVec<dim> c = IVec<dim>::Zero();
    for (double& sign : checkerboard_) {
      sign = c.sum() % 2 == 0 ? 1.0 : -1.0;
      for (int a = 0; a < dim; ++a) {
        if (++c[a] < fine.cells[a]) break;
        c[a] = 0;
      }
    }
  }
  // Bottom: pseudo-inverse of the coarsest matrix over its fluid cells.
  const CellOperator<dim>& bottom = op(level_count() - 1);
  std::vector<std::int64_t> compact(static_cast<std::size_t>(bottom.cell_count()), -1);
  for (std::int64_t c = 0; c < bottom.cell_count(); ++c)
    if (bottom.type[c] == CellType::fluid) {
      compact[c] = static_cast<std::int64_t>(bottom_cells_.size());
      bottom_cells_.push_back(c);
    }
  const auto m = static_cast<Eigen::Index>(bottom_cells_.size());
  if (m == 0) return;  // no fluid cells: M = 0
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, m);
  bottom.for_each_entry([&](std::int64_t row, std::int64_t col, double v) { A(compact[row], compact[col]) = v; });
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(A);
  const Eigen::VectorXd& lambda = eigen.eigenvalues();
  const double cutoff = 1e-10 * lambda.cwiseAbs().maxCoeff();
  Eigen::VectorXd inverse(m);
  for (Eigen::Index i = 0; i < m; ++i) inverse[i] = lambda[i] > cutoff ? 1.0 / lambda[i] : 0.0;
  bottom_pinv_ = eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
}

template <int dim>
void Multigrid<dim>::gauss_seidel(int l, int colour) {
  // Poisson only: cells of one colour ((sum of coordinates) % 2) couple only to the other
  // colour, so the update is in place and parallel over lines.
  Level& level = levels_[l];
  const CellOperator<dim>& o = op(l);
  const double h2 = o.dx * o.dx;
  const int nx = o.cells[0];
  std::array<std::int64_t, dim> stride{};
  stride[0] = 1;
  for (int a = 1; a < dim; ++a) stride[a] = stride[a - 1] * o.cells[a - 1];
  const CellType* type = o.type.data();
  double* x = level.x.data();
  const double* b = level.b.data();
  if (o.is_periodic()) {
    // Even counts on periodic axes (checked at construction): the wrapped neighbours of a
    // cell still have the other colour.
    detail::parallel_for_lines<dim>(o.cells, [&](IVec<dim> c, std::int64_t base) {
      for (c[0] = (colour + c.sum()) % 2; c[0] < nx; c[0] += 2) {  // c[0] = 0 on entry
        const std::int64_t ci = base + c[0];
        if (type[ci] != CellType::fluid) continue;
        double sum = h2 * b[ci];
        for (int a = 0; a < dim; ++a)
          for (int side : {-1, 1}) {
            const std::int64_t nb = detail::shifted_index<dim>(c, side * IVec<dim>::Unit(a), o.cells, o.periodic);
            if (nb >= 0 && type[nb] == CellType::fluid) sum += x[nb];
          }
        x[ci] = sum / (2.0 * dim);
      }
    });
    return;
  }
  // x is 0 on every non-fluid cell (only fluid cells are ever written), so a neighbour needs
  // no type test: an empty neighbour adds 0 (p = 0), and a missing one past a box face reads
  // the zero line instead. The x faces are peeled off the loop.
  const std::vector<double> zero_line(static_cast<std::size_t>(nx), 0.0);
  detail::parallel_for_lines<dim>(o.cells, [&](const IVec<dim>& c, std::int64_t base) {
    std::array<const double*, 2 * (dim - 1)> across{};
    for (int a = 1; a < dim; ++a) {
      across[2 * (a - 1)] = c[a] > 0 ? x + base - stride[a] : zero_line.data();
      across[2 * (a - 1) + 1] = c[a] + 1 < o.cells[a] ? x + base + stride[a] : zero_line.data();
    }
    double* line = x + base;
    const double* rhs = b + base;
    const CellType* line_type = type + base;
    auto update = [&](int i, double sum) {
      for (const double* neighbour : across) sum += neighbour[i];
      line[i] = sum * (1.0 / (2.0 * dim));
    };
    const int first = (colour + c.sum()) % 2;
    if (nx == 1) {
      if (first == 0 && line_type[0] == CellType::fluid) update(0, h2 * rhs[0]);
      return;
    }
    if (first == 0 && line_type[0] == CellType::fluid) update(0, h2 * rhs[0] + line[1]);
    const int last = nx - 1;
    for (int i = first == 0 ? 2 : 1; i < last; i += 2)
      if (line_type[i] == CellType::fluid) update(i, h2 * rhs[i] + line[i - 1] + line[i + 1]);
    if ((last - first) % 2 == 0 && line_type[last] == CellType::fluid) update(last, h2 * rhs[last] + line[last - 1]);
  });
}

template <int dim>
void Multigrid<dim>::rotated_gauss_seidel(int l, int parity) {
  // 2D NodeCell: (A p)_c = sum over the corners n of c of beta_n (p_c - p_c'(n)) / (2 dx^2),
  // c'(n) the cell diagonally opposite c across n (multigrid.h). Cells couple only to cells
  // one column over, so the columns of one parity update in place and in parallel. x is 0
  // off the fluid cells, and a cell past a box face has p = 0 (the zero line, or the peeled
  // x faces).
  if constexpr (dim == 2) {
    Level& level = levels_[l];
    const CellOperator<dim>& o = op(l);
    const double two_h2 = 2.0 * o.dx * o.dx;
    const int nx = o.cells[0], ny = o.cells[1];
    const CellType* type = o.type.data();
    const double* beta = o.beta.data();
    const double* b = level.b.data();
    double* x = level.x.data();
    if (o.is_periodic()) {
      detail::parallel_for_lines<dim>(o.cells, [&](IVec<dim> c, std::int64_t base) {
        for (c[0] = parity; c[0] < nx; c[0] += 2) {
          const std::int64_t ci = base + c[0];
          if (type[ci] != CellType::fluid) continue;
          double sum = two_h2 * b[ci], weight = 0.0;
          for (int k = 0; k < 4; ++k) {
            const IVec<dim> corner = c + IVec<dim>(k & 1, k >> 1);
            const double w = beta[o.node_index(corner)];
            weight += w;
            const std::int64_t cj =
                detail::shifted_index<dim>(2 * corner - c - IVec<dim>::Ones(), IVec<dim>::Zero(), o.cells, o.periodic);
            if (cj >= 0) sum += w * x[cj];
          }
          if (weight > 0.0) x[ci] = sum / weight;
        }
      });
      return;
    }
    const std::vector<double> zero_line(static_cast<std::size_t>(nx), 0.0);
    const std::int64_t node_row = nx + 1;
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j) {
        const double* below = j > 0 ? x + std::int64_t(j - 1) * nx : zero_line.data();
        const double* above = j + 1 < ny ? x + std::int64_t(j + 1) * nx : zero_line.data();
        const double* beta_lo = beta + std::int64_t(j) * node_row;  // nodes (i, j), (i + 1, j)
        const double* beta_hi = beta_lo + node_row;                 // nodes (i, j + 1), (i + 1, j + 1)
        const std::int64_t base = std::int64_t(j) * nx;
        for (int i = parity; i < nx; i += 2) {
          if (type[base + i] != CellType::fluid) continue;
          const double w00 = beta_lo[i], w10 = beta_lo[i + 1], w01 = beta_hi[i], w11 = beta_hi[i + 1];
          const double weight = w00 + w10 + w01 + w11;
          if (weight == 0.0) continue;
          double sum = two_h2 * b[base + i];
          if (i > 0) sum += w00 * below[i - 1] + w01 * above[i - 1];
          if (i + 1 < nx) sum += w10 * below[i + 1] + w11 * above[i + 1];
          x[base + i] = sum / weight;
        }
      }
    });
  }
}

template <int dim>
void Multigrid<dim>::restrict_residual(int l) {
  Level& level = levels_[l];
  detail::apply_operator_to<dim>(op(l), level.x, level.scratch,
                                 [&level](std::int64_t c, double Ax) { level.r[c] = level.b[c] - Ax; });
  restrict_to_coarse(l, level.r);
}

template <int dim>
void Multigrid<dim>::restrict_to_coarse(int l, const std::vector<double>& fine) {
  // R = P^T / 2^dim, one axis at a time; coarse empty cells are not unknowns.
  const CellOperator<dim>& c = op(l + 1);
  IVec<dim> extent = op(l).cells;
  std::vector<double>& in = transfer_in_;
  std::vector<double>& out = transfer_out_;
  const std::vector<double>* from = &fine;  // the first axis reads `fine` itself
  for (int a = 0; a < dim; ++a) {
    IVec<dim> next = extent;
    next[a] = c.cells[a];
    transfer_axis<dim>(*from, extent, out, next, a, false, c.kind == CellOperator<dim>::Kind::poisson, c.periodic[a]);
    in.swap(out);
    from = &in;
    extent = next;
  }
  std::vector<double>& coarse_b = levels_[l + 1].b;
  const double scale = 1.0 / (1 << dim);
  for_each_entry(coarse_b.size(),
                 [&](std::size_t i) { coarse_b[i] = c.type[i] == CellType::fluid ? scale * in[i] : 0.0; });
}

template <int dim>
void Multigrid<dim>::prolong_add(int coarse_level) {
  const CellOperator<dim>& f = op(coarse_level - 1);
  IVec<dim> extent = op(coarse_level).cells;
  std::vector<double>& in = transfer_in_;
  std::vector<double>& out = transfer_out_;
  const std::vector<double>* from = &levels_[coarse_level].x;  // the first axis reads it itself
  for (int a = 0; a < dim; ++a) {
    IVec<dim> next = extent;
    next[a] = f.cells[a];
    transfer_axis<dim>(*from, extent, out, next, a, true, f.kind == CellOperator<dim>::Kind::poisson, f.periodic[a]);
    in.swap(out);
    from = &in;
    extent = next;
  }
  std::vector<double>& xf = levels_[coarse_level - 1].x;
  for_each_entry(xf.size(), [&](std::size_t i) {
    if (f.type[i] == CellType::fluid) xf[i] += in[i];
  });
}

template <int dim>
void Multigrid<dim>::smooth(int l, bool before) {
  // Two-colour Gauss-Seidel (Poisson: red-black; 2D NodeCell: column parity), symmetric:
  // colours 0, 1 before the coarse correction, 1, 0 after.
  Level& level = levels_[l];
  void (Multigrid::*colour_sweep)(int, int) =
      op(l).kind == CellOperator<dim>::Kind::poisson ? &Multigrid::gauss_seidel : &Multigrid::rotated_gauss_seidel;
  if (before) for_each_entry(level.x.size(), [&](std::size_t i) { level.x[i] = 0.0; });
  for (int s = 0; s < options_.smoothing_sweeps; ++s) {
    (this->*colour_sweep)(l, before ? 0 : 1);
    (this->*colour_sweep)(l, before ? 1 : 0);
  }
}

template <int dim>
void Multigrid<dim>::vcycle(int l) {
  Level& level = levels_[l];
  if (l == level_count() - 1) {
    Eigen::VectorXd rhs(static_cast<Eigen::Index>(bottom_cells_.size()));
    for (std::size_t i = 0; i < bottom_cells_.size(); ++i)
      rhs[static_cast<Eigen::Index>(i)] = level.b[bottom_cells_[i]];
    const Eigen::VectorXd solution = bottom_pinv_ * rhs;
    std::fill(level.x.begin(), level.x.end(), 0.0);
    for (std::size_t i = 0; i < bottom_cells_.size(); ++i)
      level.x[bottom_cells_[i]] = solution[static_cast<Eigen::Index>(i)];
    return;
  }
  smooth(l, true);
  restrict_residual(l);
  vcycle(l + 1);
  prolong_add(l + 1);
  smooth(l, false);
}

template <int dim>
void Multigrid<dim>::apply(const std::vector<double>& r, std::vector<double>& z) {
  Level& top = levels_[0];
  copy_entries(r, top.b);
  if (checkerboard_.empty() || level_count() == 1) {
    vcycle(0);
    copy_entries(top.x, z);
    if (checkerboard_.empty()) return;
    for_each_entry(r.size(), [&](std::size_t i) { top.b[i] = checkerboard_[i] * r[i]; });
    vcycle(0);
    for_each_entry(z.size(), [&](std::size_t i) { z[i] += checkerboard_[i] * top.x[i]; });
    return;
  }
  // M = V + S V S (multigrid.h) in one pass over the fine level: S commutes with A and with
  // the smoother, so the second V-cycle's smoothing is the first's times S. With x the
  // pre-smoothed iterate, res = r - A x and c1, c2 the coarse solutions for R res and R S res,
  // z = V r + S V S r = 2 post(x + (P c1 + S P c2) / 2, r) = post(2 x + P c1 + S P c2, 2 r),
  // post being affine in (x, b). Half the fine-level work of two V-cycles; the same M.
  smooth(0, true);
  restrict_residual(0);
  vcycle(1);
  for_each_entry(top.x.size(), [&](std::size_t i) { top.x[i] *= 2.0; });
  prolong_add(1);  // 2 x + P c1
  for_each_entry(r.size(), [&](std::size_t i) { top.r[i] *= checkerboard_[i]; });
  restrict_to_coarse(0, top.r);
  vcycle(1);
  for_each_entry(r.size(), [&](std::size_t i) { top.x[i] *= checkerboard_[i]; });
  prolong_add(1);
  for_each_entry(r.size(), [&](std::size_t i) { top.x[i] *= checkerboard_[i]; });  // 2 x + P c1 + S P c2
  for_each_entry(top.b.size(), [&](std::size_t i) { top.b[i] *= 2.0; });
  smooth(0, false);
  copy_entries(top.x, z);
}

template class Multigrid<2>;
template class Multigrid<3>;

}  // namespace fluid
