#pragma once
//! Private: the matrix-free y = A x of CellOperator in gather form (each output written by one
//! task, so it runs under tbb::parallel_for without atomics), with a caller-owned scratch for
//! the nodal gradient so that iterative solvers do not reallocate it every product.
#include <fluid/pressure/cell_operator.h>

#include <vector>

namespace fluid::detail {

//! y = A x (same semantics as CellOperator::apply); `node_scratch` is resized as needed.
template <int dim>
void apply_operator(const CellOperator<dim>& op, const std::vector<double>& x, std::vector<double>& y,
                    std::vector<double>& node_scratch);

}  // namespace fluid::detail
