// The rest-state error of Zhu et al. (solid/rest_state.h): zero for a rigid motion of the rest
// shape (rotation and translation removed by shape matching), the exact mean deviation for a
// known stretch, and rest_shape undoes a homogeneous deformation about the mass centre.
#include <doctest/doctest.h>

#include <mpm/solid/rest_state.h>

#include <Eigen/Geometry>

#include <cmath>
#include <vector>

using namespace mpm;

TEST_CASE("rest-state error: rigid motions are removed, a stretch is measured") {
  std::vector<Vec<2>> X;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 3; ++j) X.emplace_back(0.1 * i, 0.1 * j);
  const std::vector<double> mass(X.size(), 2.0);
  const Mat<2> R = Eigen::Rotation2Dd(2.5).toRotationMatrix();
  std::vector<Vec<2>> x;
  for (const Vec<2>& p : X) x.push_back(R * p + Vec<2>(3.0, -1.0));
  CHECK(solid::rest_state_error(X, x, mass) < 1e-15);
  // A reflection is not a rigid motion.
  std::vector<Vec<2>> mirrored;
  for (const Vec<2>& p : X) mirrored.emplace_back(-p[0], p[1]);
  CHECK(solid::rest_state_error(X, mirrored, mass) > 0.1);
  // Stretching y by 1.1 about the centre (y = 0.1) moves the rows at 0 and 0.2 by 0.01 each:
  // the shape matching keeps R = I, so the mean deviation is (2/3) 0.01 over the diagonal.
  std::vector<Vec<2>> stretched;
  for (const Vec<2>& p : X) stretched.emplace_back(p[0], 0.1 + 1.1 * (p[1] - 0.1));
  const double diagonal = std::sqrt(0.4 * 0.4 + 0.2 * 0.2);
  CHECK(solid::rest_state_error(X, stretched, mass) == doctest::Approx(2.0 / 3.0 * 0.01 / diagonal).epsilon(1e-12));
}

TEST_CASE("rest shape: a homogeneously deformed body maps back to its rest shape") {
  std::vector<Vec<3>> X;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 2; ++k) X.emplace_back(i, 2.0 * j, 0.5 * k);
  const std::vector<double> mass(X.size(), 1.0);
  Mat<3> F;
  F << 1.2, 0.1, 0.0, 0.0, -0.5, 0.2, 0.1, 0.0, 0.9;  // inverted
  std::vector<Vec<3>> x;
  for (const Vec<3>& p : X) x.push_back(F * p + Vec<3>(1, 2, 3));
  const std::vector<Vec<3>> rest = solid::rest_shape(x, std::vector<Mat<3>>(x.size(), F), mass);
  CHECK(solid::rest_state_error(X, rest, mass) < 1e-14);
}
