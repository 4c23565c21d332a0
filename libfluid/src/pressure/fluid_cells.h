#pragma once
//! Private: what every back-end does to b and p before it solves on the fluid cells only.
#include <fluid/pressure/cell_operator.h>

#include <cstdint>
#include <vector>

namespace fluid::detail {

//! b restricted to fluid cells (empty cells 0), so that residuals measure fluid cells only.
template <int dim>
std::vector<double> fluid_rhs(const CellOperator<dim>& op, const std::vector<double>& b) {
  std::vector<double> masked(static_cast<std::size_t>(op.cell_count()), 0.0);
  for (std::size_t c = 0; c < masked.size(); ++c)
    if (op.type[c] == CellType::fluid) masked[c] = b[c];
  return masked;
}

//! Keeps the initial guess when it has the cell count (else 0) and sets p = 0 in empty cells.
template <int dim>
void prepare_guess(const CellOperator<dim>& op, std::vector<double>& p) {
  const auto n = static_cast<std::size_t>(op.cell_count());
  if (p.size() != n) p.assign(n, 0.0);
  for (std::size_t c = 0; c < n; ++c)
    if (op.type[c] != CellType::fluid) p[c] = 0.0;
}

//! Compact numbering of the fluid cells (-1 for empty cells) and its inverse.
template <int dim>
std::int64_t number_fluid_cells(const CellOperator<dim>& op, std::vector<std::int64_t>& compact,
                                std::vector<std::int64_t>& cell_of) {
  compact.assign(static_cast<std::size_t>(op.cell_count()), -1);
  cell_of.clear();
  for (std::size_t c = 0; c < compact.size(); ++c)
    if (op.type[c] == CellType::fluid) {
      compact[c] = static_cast<std::int64_t>(cell_of.size());
      cell_of.push_back(static_cast<std::int64_t>(c));
    }
  return static_cast<std::int64_t>(cell_of.size());
}

}  // namespace fluid::detail
