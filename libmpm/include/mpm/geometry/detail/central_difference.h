#pragma once
//! The unit normal of a sampled signed distance field, from its gradient by central differences.
#include <mpm/core/types.h>

namespace mpm::geometry::detail {

//! grad phi / |grad phi| at x, with (phi(x + h e_i) - phi(x - h e_i)) / 2h per axis; the zero
//! vector where phi is flat (beyond the narrow band of a level set, where no direction is known).
template <int dim, class Phi>
Vec<dim> normal_by_central_differences(const Phi& phi, const Vec<dim>& x, double h) {
  Vec<dim> gradient;
  for (int i = 0; i < dim; ++i) {
    const Vec<dim> step = h * Vec<dim>::Unit(i);
    gradient[i] = phi(Vec<dim>(x + step)) - phi(Vec<dim>(x - step));
  }
  const double length = gradient.norm();
  return length > 0.0 ? Vec<dim>(gradient / length) : Vec<dim>::Zero();
}

}  // namespace mpm::geometry::detail
