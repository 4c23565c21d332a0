#pragma once
//! Cofactor matrix cof(F) = det(F) F^-T = d(det F)/dF and its differential. Defined for every F,
//! singular or inverted, which is why the Neo-Hookean stress is written with it.
#include <mpm/core/types.h>

#include <Eigen/Geometry>

namespace mpm::constitutive::detail {

inline Mat<2> cofactor(const Mat<2>& F) {
  Mat<2> C;
  C << F(1, 1), -F(1, 0), -F(0, 1), F(0, 0);
  return C;
}

//! Columns of cof(F) are cross products of the columns f_i of F: c_0 = f_1 x f_2, and cyclic.
inline Mat<3> cofactor(const Mat<3>& F) {
  Mat<3> C;
  C.col(0) = F.col(1).cross(F.col(2));
  C.col(1) = F.col(2).cross(F.col(0));
  C.col(2) = F.col(0).cross(F.col(1));
  return C;
}

//! d cof(F)[dF]: cof is linear in 2D.
inline Mat<2> cofactor_differential(const Mat<2>&, const Mat<2>& dF) { return cofactor(dF); }

//! d cof(F)[dF]: product rule on each cross product.
inline Mat<3> cofactor_differential(const Mat<3>& F, const Mat<3>& dF) {
  Mat<3> dC;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    dC.col(i) = dF.col(j).cross(F.col(k)) + F.col(j).cross(dF.col(k));
  }
  return dC;
}

}  // namespace mpm::constitutive::detail
