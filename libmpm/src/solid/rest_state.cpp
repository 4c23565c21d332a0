#include <mpm/core/error.h>
#include <mpm/solid/rest_state.h>

#include <Eigen/LU>
#include <Eigen/SVD>

#include <cmath>

namespace mpm::solid {

namespace {
template <int dim>
Vec<dim> mass_centre(const std::vector<Vec<dim>>& x, const std::vector<double>& mass) {
  Vec<dim> c = Vec<dim>::Zero();
  double m = 0.0;
  for (std::size_t p = 0; p < x.size(); ++p) {
    c += mass[p] * x[p];
    m += mass[p];
  }
  return m > 0.0 ? Vec<dim>(c / m) : c;
}
}  // namespace

template <int dim>
std::vector<Vec<dim>> rest_shape(const std::vector<Vec<dim>>& x, const std::vector<Mat<dim>>& F,
                                 const std::vector<double>& mass) {
  const Vec<dim> c = mass_centre(x, mass);
  std::vector<Vec<dim>> X(x.size());
  for (std::size_t p = 0; p < x.size(); ++p) {
    MPM_VERIFY(std::fabs(F[p].determinant()) > 1e-12, Error,
               "rest_shape: particle " + std::to_string(p) + " has a singular deformation gradient");
    X[p] = c + F[p].inverse() * (x[p] - c);
  }
  return X;
}

template <int dim>
double rest_state_error(const std::vector<Vec<dim>>& X, const std::vector<Vec<dim>>& x,
                        const std::vector<double>& mass) {
  MPM_VERIFY(X.size() == x.size() && x.size() == mass.size(), Error, "rest_state_error: sizes differ");
  if (x.empty()) return 0.0;
  const Vec<dim> Xc = mass_centre(X, mass), xc = mass_centre(x, mass);
  Mat<dim> A = Mat<dim>::Zero();
  Vec<dim> lo = X.front(), hi = X.front();
  for (std::size_t p = 0; p < x.size(); ++p) {
    A.noalias() += mass[p] * (x[p] - xc) * (X[p] - Xc).transpose();
    lo = lo.cwiseMin(X[p]);
    hi = hi.cwiseMax(X[p]);
  }
  const Eigen::JacobiSVD<Mat<dim>> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat<dim> D = Mat<dim>::Identity();  // a rotation, never a reflection
  D(dim - 1, dim - 1) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Mat<dim> R = svd.matrixU() * D * svd.matrixV().transpose();
  double sum = 0.0;
  for (std::size_t p = 0; p < x.size(); ++p) sum += (R * (X[p] - Xc) + xc - x[p]).norm();
  const double diagonal = (hi - lo).norm();
  return diagonal > 0.0 ? sum / x.size() / diagonal : 0.0;
}

template std::vector<Vec<2>> rest_shape(const std::vector<Vec<2>>&, const std::vector<Mat<2>>&,
                                        const std::vector<double>&);
template std::vector<Vec<3>> rest_shape(const std::vector<Vec<3>>&, const std::vector<Mat<3>>&,
                                        const std::vector<double>&);
template double rest_state_error(const std::vector<Vec<2>>&, const std::vector<Vec<2>>&, const std::vector<double>&);
template double rest_state_error(const std::vector<Vec<3>>&, const std::vector<Vec<3>>&, const std::vector<double>&);

}  // namespace mpm::solid
