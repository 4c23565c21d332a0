// Multigrid over sign-modulated coarse spaces (definitions and choices in
// modulated_multigrid.h).
#include <fluid/pressure/modulated_multigrid.h>

#include "fluid_cells.h"

#include <mpm/core/error.h>
#include <mpm/core/solve/vector_space.h>

#include <Eigen/Eigenvalues>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <optional>
#include <utility>

namespace fluid {

namespace {

using mpm::solve::for_each_entry;
using Triplet = Eigen::Triplet<double>;

//! Spaces with fewer unknowns are smoothed and multiplied in one thread: below this size the
//! colour sweeps and row blocks cost more to schedule than they save.
constexpr Eigen::Index kParallelRows = 4096;

//! y = A x over the rows of A in parallel (Eigen's sparse products run in one thread).
template <class Matrix>
void parallel_multiply(const Matrix& A, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  y.resize(A.rows());
  const int* start = A.outerIndexPtr();
  const int* column = A.innerIndexPtr();
  const double* value = A.valuePtr();
  const auto rows = [&](Eigen::Index first, Eigen::Index last) {
    for (Eigen::Index i = first; i < last; ++i) {
      double sum = 0.0;
      for (int k = start[i]; k < start[i + 1]; ++k) sum += value[k] * x[column[k]];
      y[i] = sum;
    }
  };
  if (A.rows() < kParallelRows) return rows(0, A.rows());
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, A.rows(), 2048),
                    [&](const auto& r) { rows(r.begin(), r.end()); });
}

//! The rows of each colour (c = sum_a (q_a mod 3) 3^a of the box coordinates q), or none when
//! two rows of one colour are coupled (a periodic axis whose extent is not a multiple of 3).
//! The coarse Galerkin stencils reach two cells along each axis, so a colour's rows, 3 apart,
//! never meet.
template <int dim, class Matrix>
std::vector<std::vector<int>> colour_rows(const Matrix& A, const std::vector<IVec<dim>>& cell) {
  const Eigen::Index n = A.rows();
  std::vector<int> colour(static_cast<std::size_t>(n));
  int colours = 1;
  for (int a = 0; a < dim; ++a) colours *= 3;
  for (Eigen::Index i = 0; i < n; ++i) {
    int c = 0;
    for (int a = dim - 1; a >= 0; --a) c = 3 * c + cell[static_cast<std::size_t>(i)][a] % 3;
    colour[static_cast<std::size_t>(i)] = c;
  }
  const int* start = A.outerIndexPtr();
  const int* column = A.innerIndexPtr();
  for (Eigen::Index i = 0; i < n; ++i)
    for (int k = start[i]; k < start[i + 1]; ++k)
      if (column[k] != i && colour[static_cast<std::size_t>(column[k])] == colour[static_cast<std::size_t>(i)])
        return {};
  std::vector<std::vector<int>> rows(static_cast<std::size_t>(colours));
  for (Eigen::Index i = 0; i < n; ++i)
    rows[static_cast<std::size_t>(colour[static_cast<std::size_t>(i)])].push_back(int(i));
  return rows;
}

//! Index of box coordinates q in `extent`, x fastest.
template <int dim>
std::int64_t box_index(const IVec<dim>& q, const IVec<dim>& extent) {
  std::int64_t index = 0;
  for (int a = dim - 1; a >= 0; --a) index = index * extent[a] + q[a];
  return index;
}

//! Rows with K values per entry (one per sign pattern) over one sparsity structure.
struct PatternRows {
  std::vector<int> start{0}, column;
  std::vector<double> value;  //!< entry e, pattern k at e * K + k
};

//! Rows [0, rows) with K values per entry, made in blocks of rows in parallel and joined in
//! order: fill(first, last, part) appends rows first .. last - 1 to `part` (a row ends with
//! part.start.push_back). The blocks (about 1 024 rows, at most 64) depend on the row count
//! only: the same rows on any thread count.
template <class Fill>
PatternRows rows_in_blocks(Eigen::Index rows, int K, const Fill& fill) {
  const Eigen::Index blocks = std::clamp<Eigen::Index>(rows / 1024, 1, 64);
  std::vector<PatternRows> parts(static_cast<std::size_t>(blocks));
  tbb::parallel_for(Eigen::Index{0}, blocks, [&](Eigen::Index block) {
    fill(rows * block / blocks, rows * (block + 1) / blocks, parts[static_cast<std::size_t>(block)]);
  });
  // Each block copied in parallel to its place.
  std::vector<std::size_t> first_row(parts.size() + 1, 0), first_entry(parts.size() + 1, 0);
  for (std::size_t b = 0; b < parts.size(); ++b) {
    first_row[b + 1] = first_row[b] + parts[b].start.size() - 1;
    first_entry[b + 1] = first_entry[b] + parts[b].column.size();
  }
  PatternRows joined;
  joined.start.resize(first_row.back() + 1);
  joined.column.resize(first_entry.back());
  joined.value.resize(first_entry.back() * static_cast<std::size_t>(K));
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t b) {
    const PatternRows& part = parts[b];
    for (std::size_t r = 1; r < part.start.size(); ++r)  // entry 0: the previous block's end (or 0)
      joined.start[first_row[b] + r] = static_cast<int>(first_entry[b]) + part.start[r];
    std::copy(part.column.begin(), part.column.end(), joined.column.begin() + std::ptrdiff_t(first_entry[b]));
    std::copy(part.value.begin(), part.value.end(), joined.value.begin() + std::ptrdiff_t(first_entry[b] * K));
  });
  return joined;
}

//! Gustavson's product, row by row with a dense accumulator, for K patterns at once: output
//! row i is the sum over the entries (m, w) of left row i of w * sign_k(m) * (right row m)_k.
//! `right(m, emit)` calls emit(column, values, stride) for each entry of row m, the value of
//! pattern k at values[k * stride] (stride 0: one value for all). One pass serves every
//! pattern. Rows are independent: blocks of rows run in parallel, each with its own
//! accumulator (rows_in_blocks).
template <class Right>
PatternRows multiply_patterns(const Eigen::SparseMatrix<double, Eigen::RowMajor>& left,
                              const std::vector<Eigen::VectorXd>& signs, Eigen::Index columns, const Right& right) {
  const int K = static_cast<int>(signs.size());
  return rows_in_blocks(left.rows(), K, [&](Eigen::Index first, Eigen::Index last, PatternRows& out) {
    std::vector<double> accumulator(static_cast<std::size_t>(columns * K), 0.0);
    std::vector<char> seen(static_cast<std::size_t>(columns), 0);
    std::vector<int> touched;
    std::vector<double> weight(static_cast<std::size_t>(K));
    for (Eigen::Index i = first; i < last; ++i) {
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator l(left, i); l; ++l) {
        for (int k = 0; k < K; ++k) weight[k] = l.value() * signs[k][l.col()];
        right(l.col(), [&](int j, const double* values, int stride) {
          if (!seen[j]) {
            seen[j] = 1;
            touched.push_back(j);
          }
          double* sum = &accumulator[static_cast<std::size_t>(j) * K];
          for (int k = 0; k < K; ++k) sum[k] += weight[k] * values[k * stride];
        });
      }
      std::sort(touched.begin(), touched.end());
      for (int j : touched) {
        out.column.push_back(j);
        double* sum = &accumulator[static_cast<std::size_t>(j) * K];
        out.value.insert(out.value.end(), sum, sum + K);
        std::fill(sum, sum + K, 0.0);
        seen[j] = 0;
      }
      touched.clear();
      out.start.push_back(static_cast<int>(out.column.size()));
    }
  });
}

//! The Galerkin operators A_k = P0^T S_k A S_k P0 (R0 = P0^T) of every sign vector s_k.
std::vector<Eigen::SparseMatrix<double, Eigen::RowMajor>> modulated_galerkin(
    const Eigen::SparseMatrix<double, Eigen::RowMajor>& A, const Eigen::SparseMatrix<double, Eigen::RowMajor>& P0,
    const Eigen::SparseMatrix<double, Eigen::RowMajor>& R0, const std::vector<Eigen::VectorXd>& signs) {
  using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;
  const int K = static_cast<int>(signs.size());
  // T_k = A S_k P0: row m of P0 carries the same weight for every pattern.
  const PatternRows T = multiply_patterns(A, signs, P0.cols(), [&](Eigen::Index m, auto&& emit) {
    for (Matrix::InnerIterator p(P0, m); p; ++p) emit(static_cast<int>(p.col()), &p.valueRef(), 0);
  });
  // A_k = R0 S_k T_k.
  const PatternRows C = multiply_patterns(R0, signs, P0.cols(), [&](Eigen::Index m, auto&& emit) {
    for (int e = T.start[m]; e < T.start[m + 1]; ++e) emit(T.column[e], &T.value[static_cast<std::size_t>(e) * K], 1);
  });
  std::vector<Matrix> result(static_cast<std::size_t>(K));
  tbb::parallel_for(0, K, [&](int k) {
    std::vector<double> values(C.column.size());
    for (std::size_t e = 0; e < values.size(); ++e) values[e] = C.value[e * K + k];
    result[static_cast<std::size_t>(k)] = Eigen::Map<const Matrix>(
        R0.rows(), P0.cols(), static_cast<Eigen::Index>(values.size()), C.start.data(), C.column.data(), values.data());
  });
  return result;
}

//! The median over the unknowns of the local energy ratio (A v)_i / (A_ii v_i) (v_i != 0).
//! A median, not the global v^T A v / v^T diag(A) v: a pattern that is near-null on most of
//! the space stays near-null when a minority of cells (droplets, whose rows are diagonal)
//! add ratio 1. With the global ratio, 2 % droplet cells in the air of the 32^3 dam break cut
//! the tree from 51 to 36 spaces and MGPCG went from 10 to 29 iterations.
double median_energy_ratio(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A, const Eigen::VectorXd& diagonal,
                           const Eigen::VectorXd& v) {
  const Eigen::VectorXd Av = A * v;
  std::vector<double> ratio;
  ratio.reserve(static_cast<std::size_t>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (v[i] != 0.0 && diagonal[i] > 0.0) ratio.push_back(Av[i] / (diagonal[i] * v[i]));
  if (ratio.empty()) return 1.0;
  auto middle = ratio.begin() + static_cast<std::ptrdiff_t>(ratio.size() / 2);
  std::nth_element(ratio.begin(), middle, ratio.end());
  return *middle;
}

//! S_k = diag((-1)^(k . q)) over the cells q (bit a of `pattern`: a sign flip along axis a).
template <int dim>
Eigen::VectorXd sign_of_pattern(const std::vector<IVec<dim>>& cell, int pattern) {
  Eigen::VectorXd sign(static_cast<Eigen::Index>(cell.size()));
  for (std::size_t i = 0; i < cell.size(); ++i) {
    int parity = 0;
    for (int a = 0; a < dim; ++a) parity += (pattern >> a & 1) * cell[i][a];
    sign[static_cast<Eigen::Index>(i)] = parity % 2 == 0 ? 1.0 : -1.0;
  }
  return sign;
}

//! The mean of A's diagonal (0 for an empty A): the scale of an operator (refresh).
double mean_diagonal(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A) {
  return A.rows() > 0 ? A.diagonal().sum() / static_cast<double>(A.rows()) : 0.0;
}

//! Box coordinates of the cells with the given indices (x fastest) in a box of `extent`.
template <int dim>
std::vector<IVec<dim>> box_cells(const std::vector<std::int64_t>& index, const IVec<dim>& extent) {
  std::vector<IVec<dim>> cells;
  cells.reserve(index.size());
  for (std::int64_t c : index) {
    IVec<dim> q;
    for (int a = 0; a < dim; ++a) {
      q[a] = static_cast<int>(c % extent[a]);
      c /= extent[a];
    }
    cells.push_back(q);
  }
  return cells;
}

}  // namespace

template <int dim>
ModulatedMultigrid<dim>::ModulatedMultigrid(const CellOperator<dim>& op, const Options& options)
    : options_(options), periodic_(op.periodic) {
  mpm::verify<mpm::InputError>(options.near_null_ratio > 0.0, "ModulatedMultigrid: near_null_ratio must be > 0");
  mpm::verify<mpm::InputError>(options.additive_depth >= 0, "ModulatedMultigrid: additive_depth must be >= 0");
  std::vector<std::int64_t> compact;
  detail::number_fluid_cells(op, compact, fluid_cells_);
  fine_ = std::make_unique<Space>();
  Space& fine = *fine_;
  fine.extent = op.cells;
  fine.cell = box_cells<dim>(fluid_cells_, op.cells);
  fine.A = fine_matrix(op, compact);
  built_trace_ = mean_diagonal(fine.A);
  build(fine);
}

template <int dim>
typename ModulatedMultigrid<dim>::Matrix ModulatedMultigrid<dim>::fine_matrix(
    const CellOperator<dim>& op, const std::vector<std::int64_t>& compact) {
  // for_each_entry gives the rows in cell order, each row's columns ascending and merged, and
  // the fluid cells are numbered in cell order: the entries are the compressed rows as they
  // come. Blocks of rows are assembled in parallel (a row's entries cost some 60 mobility
  // products: serial, the assembly before every solve held back a 16-core solve) and joined in
  // order: the same matrix on any thread count.
  const auto n = static_cast<Eigen::Index>(fluid_cells_.size());
  const PatternRows rows = rows_in_blocks(n, 1, [&](Eigen::Index first_row, Eigen::Index last_row, PatternRows& part) {
    if (first_row == last_row) return;
    const std::int64_t first = fluid_cells_[static_cast<std::size_t>(first_row)];
    const std::int64_t last = last_row < n ? fluid_cells_[static_cast<std::size_t>(last_row)] : op.cell_count();
    part.start.reserve(static_cast<std::size_t>(last_row - first_row) + 1);
    op.for_each_entry(first, last, [&](std::int64_t row, std::int64_t col, double v) {
      const std::int64_t local = compact[row] - first_row;  // the row being filled, or a later one
      assert(local + 1 >= static_cast<std::int64_t>(part.start.size()));
      while (static_cast<std::int64_t>(part.start.size()) <= local)
        part.start.push_back(static_cast<int>(part.column.size()));
      part.column.push_back(static_cast<int>(compact[col]));
      part.value.push_back(v);
    });
    part.start.resize(static_cast<std::size_t>(last_row - first_row) + 1, static_cast<int>(part.column.size()));
  });
  return Eigen::Map<const Matrix>(n, n, static_cast<Eigen::Index>(rows.column.size()), rows.start.data(),
                                  rows.column.data(), rows.value.data());
}

template <int dim>
bool ModulatedMultigrid<dim>::refresh(const CellOperator<dim>& op) {
  Space& fine = *fine_;
  if (op.cells != fine.extent || op.periodic != periodic_) return false;
  std::vector<std::int64_t> compact, cells;
  detail::number_fluid_cells(op, compact, cells);
  const bool same_cells = cells == fluid_cells_;
  // New cells interpolate from the coarse cells there are; a tree without coarse spaces, or a
  // fine space small enough for a bottom inverse, is cheap to build anew.
  if (!same_cells && (fine.children.empty() || static_cast<std::int64_t>(cells.size()) <= options_.max_bottom_unknowns))
    return false;
  fluid_cells_ = std::move(cells);
  fine.A = fine_matrix(op, compact);
  // The coarse operators keep the scale of the operator they were built from; the step dt
  // scales the whole operator (a frame's last step is often much shorter), so the coarse
  // corrections are rescaled by the ratio of the traces (per cell: the cells may differ).
  const double trace = mean_diagonal(fine.A);
  coarse_scale_ = trace > 0.0 ? built_trace_ / trace : 1.0;
  if (same_cells) {
    if (!prepare(fine)) fine.children.clear();  // a bottom space: inverted again
    return true;
  }
  fine.cell = box_cells<dim>(fluid_cells_, op.cells);
  prepare(fine);                                       // coarsens: it did with children, and the box is the same
  const Space& coarse = *fine.children.front().space;  // the children share their cells
  std::vector<IVec<dim>> coarse_cell = coarse.cell;
  std::optional<Matrix> P0 = interpolation(fine, coarse.extent, coarse_cell, false);
  if (!P0) return false;
  fine.P0 = std::move(*P0);
  fine.R0 = fine.P0.transpose();
  for (Child& child : fine.children) child.sign = sign_of_pattern<dim>(fine.cell, child.pattern);
  return true;
}

template <int dim>
std::optional<typename ModulatedMultigrid<dim>::Matrix> ModulatedMultigrid<dim>::interpolation(
    const Space& s, const IVec<dim>& coarse_extent, std::vector<IVec<dim>>& coarse_cell, bool add_parents) const {
  std::vector<std::int64_t> coarse_index(static_cast<std::size_t>(coarse_extent.template cast<std::int64_t>().prod()),
                                         -1);
  for (std::size_t c = 0; c < coarse_cell.size(); ++c)
    coarse_index[box_index<dim>(coarse_cell[c], coarse_extent)] = static_cast<std::int64_t>(c);
  // A cell without off-diagonal entries (a droplet: no neighbour shares a movable node) is
  // solved exactly by the smoother; in a coarse space it would only add its energy to the
  // coarse functions of the liquid beside it. It gets no interpolation.
  std::vector<char> coupled(s.cell.size(), 0);
  for (Eigen::Index i = 0; i < s.A.outerSize(); ++i)
    for (Matrix::InnerIterator a(s.A, i); a; ++a)
      coupled[static_cast<std::size_t>(i)] |= a.col() != i && a.value() != 0.0;
  std::size_t orphans = 0;  // coupled cells whose own coarse cell is missing (refresh)
  for (std::size_t i = 0; i < s.cell.size(); ++i) {
    if (!coupled[i]) continue;
    const IVec<dim>& q = s.cell[i];
    std::int64_t& slot = coarse_index[box_index<dim>(q / 2, coarse_extent)];
    if (slot >= 0) continue;
    if (!add_parents) {
      ++orphans;
      continue;
    }
    slot = static_cast<std::int64_t>(coarse_cell.size());
    coarse_cell.push_back(q / 2);
  }
  if (static_cast<double>(orphans) > options_.max_orphan_share * static_cast<double>(s.cell.size()))
    return std::nullopt;
  std::vector<Triplet> weights;
  for (std::size_t i = 0; i < s.cell.size(); ++i) {
    if (!coupled[i]) continue;
    const IVec<dim>& q = s.cell[i];
    for (int corner = 0; corner < (1 << dim); ++corner) {
      IVec<dim> coarse;
      double w = 1.0;
      for (int a = 0; a < dim; ++a) {
        const int near = q[a] / 2;
        if ((corner >> a & 1) == 0) {
          coarse[a] = near;
          w *= 0.75;
          continue;
        }
        int far = near + (q[a] % 2 == 1 ? 1 : -1);
        if (periodic_[a]) far = (far + coarse_extent[a]) % coarse_extent[a];
        if (far < 0 || far >= coarse_extent[a]) far = near;  // mirrored at the face
        coarse[a] = far;
        w *= 0.25;
      }
      const std::int64_t column = coarse_index[box_index<dim>(coarse, coarse_extent)];
      if (column >= 0) weights.emplace_back(static_cast<int>(i), static_cast<int>(column), w);
    }
  }
  Matrix P0(static_cast<Eigen::Index>(s.cell.size()), static_cast<Eigen::Index>(coarse_cell.size()));
  P0.setFromTriplets(weights.begin(), weights.end());
  return P0;
}

template <int dim>
bool ModulatedMultigrid<dim>::prepare(Space& s) const {
  s.A.makeCompressed();  // gauss_seidel reads the raw CSR arrays
  const Eigen::Index n = s.A.rows();
  s.b = s.x = s.residual = Eigen::VectorXd::Zero(n);
  const Eigen::VectorXd diagonal = s.A.diagonal();
  s.inverse_diagonal = (diagonal.array() > 0.0).select(diagonal.cwiseInverse(), 0.0);
  s.colours.clear();
  s.bottom.resize(0, 0);
  if (n == 0) return false;
  if (n >= kParallelRows && n > options_.max_bottom_unknowns) s.colours = colour_rows<dim>(s.A, s.cell);
  if (n <= options_.max_bottom_unknowns) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(Eigen::MatrixXd(s.A));
    const Eigen::VectorXd& lambda = eigen.eigenvalues();
    const double cutoff = 1e-10 * lambda.cwiseAbs().maxCoeff();
    const Eigen::VectorXd inverse = (lambda.array() > cutoff).select(lambda.cwiseInverse(), 0.0);
    s.bottom = eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
    return false;
  }
  return detail::can_halve<dim>(s.extent, periodic_);  // else smoothed only
}

template <int dim>
void ModulatedMultigrid<dim>::build(Space& s) const {
  if (!prepare(s)) return;
  // P0: the coarse cells that own a cell of this space, and the interpolation weights.
  const IVec<dim> coarse_extent = (s.extent.array() + 1) / 2;
  std::vector<IVec<dim>> coarse_cell;
  Matrix P0 = *interpolation(s, coarse_extent, coarse_cell, true);

  // Pattern k's constant vector is v = S_k P0 1; its median energy ratio decides (header).
  const Eigen::VectorXd diagonal = s.A.diagonal();
  const Eigen::VectorXd interpolated_one = P0 * Eigen::VectorXd::Ones(P0.cols());
  // The patterns are tested in parallel (each an operator product), kept in pattern order.
  std::vector<Eigen::VectorXd> pattern_sign(1 << dim);
  std::vector<char> near_null(1 << dim, 0);
  tbb::parallel_for(0, 1 << dim, [&](int pattern) {
    Eigen::VectorXd& sign = pattern_sign[static_cast<std::size_t>(pattern)];
    sign = sign_of_pattern<dim>(s.cell, pattern);
    near_null[static_cast<std::size_t>(pattern)] =
        pattern == 0 ||
        median_energy_ratio(s.A, diagonal, sign.cwiseProduct(interpolated_one)) < options_.near_null_ratio;
  });
  std::vector<Child> children;
  std::vector<Eigen::VectorXd> signs;
  for (int pattern = 0; pattern < (1 << dim); ++pattern) {
    if (!near_null[static_cast<std::size_t>(pattern)]) continue;
    Child child;
    child.pattern = pattern;
    children.push_back(std::move(child));
    signs.push_back(std::move(pattern_sign[static_cast<std::size_t>(pattern)]));
  }
  Matrix R0 = P0.transpose();
  std::vector<Matrix> child_matrices = modulated_galerkin(s.A, P0, R0, signs);
  s.P0 = std::move(P0);
  s.R0 = std::move(R0);
  for (std::size_t k = 0; k < children.size(); ++k) {
    children[k].sign = std::move(signs[k]);
    children[k].space = std::make_unique<Space>();
    Space& coarse = *children[k].space;
    coarse.A = std::move(child_matrices[k]);
    coarse.extent = coarse_extent;
    coarse.cell = coarse_cell;
  }
  s.children = std::move(children);
  tbb::parallel_for(std::size_t{0}, s.children.size(), [&](std::size_t k) { build(*s.children[k].space); });
}

template <int dim>
template <class Fn>
void ModulatedMultigrid<dim>::for_each_space(const Space& s, Fn&& fn) {
  fn(s);
  for (const Child& child : s.children) for_each_space(*child.space, fn);
}

template <int dim>
void ModulatedMultigrid<dim>::gauss_seidel(Space& s, bool forward) const {
  const Eigen::Index n = s.A.rows();
  const int* start = s.A.outerIndexPtr();
  const int* column = s.A.innerIndexPtr();
  const double* value = s.A.valuePtr();
  double* x = s.x.data();
  auto update = [&](Eigen::Index i) {
    if (s.inverse_diagonal[i] == 0.0) return;
    double sum = s.b[i];
    for (int k = start[i]; k < start[i + 1]; ++k) sum -= value[k] * x[column[k]];
    x[i] += s.inverse_diagonal[i] * sum;
  };
  if (s.colours.empty()) {
    if (forward)
      for (Eigen::Index i = 0; i < n; ++i) update(i);
    else
      for (Eigen::Index i = n - 1; i >= 0; --i) update(i);
    return;
  }
  // Colour by colour, forward then (post-smoothing) backward: Gauss-Seidel in the colour
  // ordering and its reverse, so the V-cycle stays symmetric. Within a colour the rows are
  // independent: the result does not depend on the threads.
  const int colours = static_cast<int>(s.colours.size());
  for (int c = 0; c < colours; ++c) {
    const std::vector<int>& rows = s.colours[static_cast<std::size_t>(forward ? c : colours - 1 - c)];
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.size(), 512), [&](const auto& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k) update(rows[k]);
    });
  }
}

template <int dim>
void ModulatedMultigrid<dim>::cycle(Space& s, int depth) {
  const bool fine = depth == 0;
  if (s.bottom.size() > 0) {
    s.x.noalias() = s.bottom * s.b;
    return;
  }
  // The vector updates entry by entry in parallel (the same bits as Eigen's loops).
  const auto entries = [&s](auto&& f) { for_each_entry(static_cast<std::size_t>(s.x.size()), f); };
  entries([&](std::size_t i) { s.x[static_cast<Eigen::Index>(i)] = 0.0; });
  for (int sweep = 0; sweep < options_.smoothing_sweeps; ++sweep) gauss_seidel(s, true);
  // Child k solves for the correction S_k P0 e from the right-hand side (S_k P0)^T residual.
  auto restrict_residual = [&](const Child& child) {
    s.scratch.resize(s.x.size());
    entries([&](std::size_t i) {
      const auto k = static_cast<Eigen::Index>(i);
      s.scratch[k] = child.sign[k] * s.residual[k];
    });
    parallel_multiply(s.R0, s.scratch, child.space->b);
  };
  // The fine level's corrections are scaled by coarse_scale_ (1 unless refreshed).
  const double scale = fine ? coarse_scale_ : 1.0;
  auto add_correction = [&](const Child& child) {
    parallel_multiply(s.P0, child.space->x, s.scratch);
    entries([&](std::size_t i) {
      const auto k = static_cast<Eigen::Index>(i);
      s.x[k] += scale * (child.sign[k] * s.scratch[k]);
    });
  };
  auto update_residual = [&] {
    parallel_multiply(s.A, s.x, s.residual);
    entries([&](std::size_t i) {
      const auto k = static_cast<Eigen::Index>(i);
      s.residual[k] = s.b[k] - s.residual[k];
    });
  };
  const int K = static_cast<int>(s.children.size());
  if (depth < options_.additive_depth) {
    // Additive: all children from one residual (one product with this space's matrix). Their
    // subtrees share nothing, so they run in parallel; the sum is taken in a fixed order.
    if (K > 0) update_residual();
    for (const Child& child : s.children) restrict_residual(child);
    tbb::parallel_for(0, K, [&](int k) { cycle(*s.children[k].space, depth + 1); });
    for (const Child& child : s.children) add_correction(child);
  } else {
    // Multiplicative, children 0 .. K-1 .. 0, each from the updated residual (header).
    for (int step = 0; step < 2 * K - 1; ++step) {
      const Child& child = s.children[step < K ? step : 2 * K - 2 - step];
      update_residual();
      restrict_residual(child);
      cycle(*child.space, depth + 1);
      add_correction(child);
    }
  }
  for (int sweep = 0; sweep < options_.smoothing_sweeps; ++sweep) gauss_seidel(s, false);
}

template <int dim>
void ModulatedMultigrid<dim>::apply(const std::vector<double>& r, std::vector<double>& z) {
  z.resize(r.size());
  for_each_entry(z.size(), [&](std::size_t i) { z[i] = 0.0; });
  Space& fine = *fine_;
  if (fine.A.rows() == 0) return;
  for_each_entry(fluid_cells_.size(),
                 [&](std::size_t i) { fine.b[static_cast<Eigen::Index>(i)] = r[fluid_cells_[i]]; });
  cycle(fine, 0);
  for_each_entry(fluid_cells_.size(),
                 [&](std::size_t i) { z[fluid_cells_[i]] = fine.x[static_cast<Eigen::Index>(i)]; });
}

template <int dim>
std::vector<int> ModulatedMultigrid<dim>::fine_patterns() const {
  std::vector<int> patterns;
  for (const Child& child : fine_->children) patterns.push_back(child.pattern);
  return patterns;
}

template <int dim>
double ModulatedMultigrid<dim>::operator_complexity() const {
  double total = 0.0;
  for_each_space(*fine_, [&](const Space& s) { total += static_cast<double>(s.A.nonZeros()); });
  return fine_->A.nonZeros() > 0 ? total / static_cast<double>(fine_->A.nonZeros()) : 1.0;
}

template <int dim>
int ModulatedMultigrid<dim>::space_count() const {
  int count = 0;
  for_each_space(*fine_, [&](const Space&) { ++count; });
  return count;
}

template class ModulatedMultigrid<2>;
template class ModulatedMultigrid<3>;

}  // namespace fluid
