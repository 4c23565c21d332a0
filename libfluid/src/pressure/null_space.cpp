// Null vectors of the pressure operator among the constant and the checkerboards (see
// null_space.h): generalised eigenproblem (V^T A V) alpha = lambda (V^T V) alpha; the
// eigenvectors with lambda ~ 0 give the null vectors, orthonormalised by Gram-Schmidt.
// Combinations matter: one emptied cell of a closed cavity leaves the constant of the other
// checkerboard colour in the null space.
#include <fluid/pressure/null_space.h>
#include <mpm/core/solve/vector_space.h>

#include <Eigen/Eigenvalues>

#include <bit>
#include <cmath>

namespace fluid {

using mpm::solve::dot;

template <int dim>
std::vector<std::vector<double>> null_space_basis(const CellOperator<dim>& op) {
  std::vector<std::vector<double>> V;
  for (int S = 0; S < (1 << dim); ++S) {
    if (std::popcount(static_cast<unsigned>(S)) == 1) continue;
    std::vector<double> v(static_cast<std::size_t>(op.cell_count()), 0.0);
    IVec<dim> c = IVec<dim>::Zero();
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (op.type[i] == CellType::fluid) {
        int parity = 0;
        for (int a = 0; a < dim; ++a) parity += ((S >> a) & 1) * c[a];
        v[i] = parity % 2 ? -1.0 : 1.0;
      }
      for (int a = 0; a < dim; ++a) {
        if (++c[a] < op.cells[a]) break;
        c[a] = 0;
      }
    }
    V.push_back(std::move(v));
  }
  const int m = static_cast<int>(V.size());
  Eigen::MatrixXd G(m, m), N(m, m);  // V^T A V and V^T V
  std::vector<double> Av;
  for (int j = 0; j < m; ++j) {
    op.apply(V[j], Av);
    for (int i = 0; i < m; ++i) {
      G(i, j) = dot(V[i], Av);
      N(i, j) = dot(V[i], V[j]);
    }
  }
  // N: the candidates' Gram matrix, SPD while the fluid cells are not all of one colour; a
  // tiny ridge keeps it so.
  N += 1e-12 * N.trace() * Eigen::MatrixXd::Identity(m, m);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(G, N);
  const double largest = eig.eigenvalues().cwiseAbs().maxCoeff();
  std::vector<std::vector<double>> basis;
  for (int k = 0; k < m; ++k) {
    if (std::abs(eig.eigenvalues()[k]) > 1e-10 * largest && largest > 0.0) continue;
    std::vector<double> v(static_cast<std::size_t>(op.cell_count()), 0.0);
    for (int j = 0; j < m; ++j)
      for (std::size_t i = 0; i < v.size(); ++i) v[i] += eig.eigenvectors()(j, k) * V[j][i];
    remove_components(basis, v);
    const double norm = std::sqrt(dot(v, v));
    if (norm <= 1e-8) continue;
    for (double& x : v) x /= norm;
    basis.push_back(std::move(v));
  }
  return basis;
}

void remove_components(const std::vector<std::vector<double>>& basis, std::vector<double>& v) {
  for (const auto& q : basis) {
    const double vq = dot(v, q);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] -= vq * q[i];
  }
}

template std::vector<std::vector<double>> null_space_basis(const CellOperator<2>&);
template std::vector<std::vector<double>> null_space_basis(const CellOperator<3>&);

}  // namespace fluid
