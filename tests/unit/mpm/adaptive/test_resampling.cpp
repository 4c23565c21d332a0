// Particle resampling on the adaptive grid (adaptive/resampling.h):
//  - random rotations are proper rotations, the same for the same key;
//  - the deformation average returns F for equal F (inverted included), the mean rotation of
//    rotations, the mean of commuting stretches, and stays near the arithmetic mean close to
//    F = I (where the SVD factors are not unique);
//  - a split conserves mass, volume, the first moment and linear momentum to round-off, and
//    changes the angular momentum sum m x x v by exactly m eps:(C (b/4)^2);
//  - a merge conserves mass, volume, the mass centre and linear momentum to round-off and
//    drops exactly the children's spread angular momentum; a split then merge restores the
//    particle;
//  - the surface distance counts face steps of the finest cells, with coarse particles' boxes
//    covering the cells they stand for;
//  - resampling a block merges deep inside and splits near the surface by the bands and
//    guards, conserves mass and momentum, is deterministic, and keeps every channel of the
//    particles it leaves alone;
//  - the resample stage with max_travel resamples when the particles may have moved that far
//    since the last resampling, and at the same steps after a restart from its carried data.
#include <mpm/adaptive/particle_levels.h>
#include <mpm/adaptive/resampling.h>
#include <mpm/core/stages/resample_particles.h>

#include <doctest/doctest.h>
#include <Eigen/Geometry>

#include "angular_momentum.h"

#include <array>
#include <map>
#include <random>

using namespace mpm;
using namespace mpm::adaptive;
using mpm::test::cross;
using mpm::test::spin;

namespace {

struct Totals {
  double mass = 0.0, volume = 0.0;
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero(),
                  angular = Eigen::Vector3d::Zero();
};
template <int dim>
Totals totals(const Particles<dim>& P) {
  Totals t;
  for (std::size_t p = 0; p < P.size(); ++p) {
    t.mass += P.mass[p];
    t.volume += P.volume0[p];
    t.momentum.head<dim>() += P.mass[p] * P.v[p];
    t.moment.head<dim>() += P.mass[p] * P.x[p];
    t.angular += P.mass[p] * cross<dim>(P.x[p], P.v[p]);
  }
  return t;
}

template <int dim>
CellTree<dim> tree_of(int levels, int base = 4, double dx0 = 1.0) {
  return CellTree<dim>(Vec<dim>::Zero(), IVec<dim>::Constant(base), dx0, levels);
}

// Particles with the solid's channels, a level channel, random v, C, F and plastic state.
template <int dim>
Particles<dim> solid_particles(const CellTree<dim>& tree) {
  Particles<dim> P;
  add_level_channel(P, tree);
  P.template add_channel<Mat<dim>>("F", Mat<dim>::Identity(), {true, true, "J"});
  P.template add_channel<double>("plastic", 0.0, {true, true});
  return P;
}
template <int dim>
void randomise(Particles<dim>& P, std::size_t p, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int a = 0; a < dim; ++a) P.v[p][a] = u(rng);
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) {
      P.C[p](i, j) = u(rng);
      P.template channel<Mat<dim>>("F")[p](i, j) = (i == j ? 1.0 : 0.0) + 0.3 * u(rng);
    }
  P.template channel<double>("plastic")[p] = u(rng);
  P.mass[p] = 1.0 + 0.5 * u(rng);
  P.volume0[p] = 1e-3 * (1.0 + 0.5 * u(rng));
}

constexpr double tight = 1e-12;

// The particles of `before` that resampling left alone (same position and level: not split,
// not merged) are each in `after` once with every channel equal: returns how many.
template <int dim>
std::size_t untouched_particles_kept(const Particles<dim>& before, const Particles<dim>& after) {
  const auto& level_before = before.template channel<std::uint16_t>(kParticleLevel);
  const auto& level_after = after.template channel<std::uint16_t>(kParticleLevel);
  const auto key = [](const Vec<dim>& x) {
    std::array<double, dim> k;
    for (int a = 0; a < dim; ++a) k[a] = x[a];
    return k;
  };
  std::map<std::array<double, dim>, std::size_t> row_of;  // random positions: distinct
  for (std::size_t p = 0; p < after.size(); ++p) row_of.emplace(key(after.x[p]), p);
  std::size_t kept = 0;
  for (std::size_t p = 0; p < before.size(); ++p) {
    const auto it = row_of.find(key(before.x[p]));
    if (it == row_of.end() || level_after[it->second] != level_before[p]) continue;
    before.for_each_channel([&](const ChannelInfo& info, const auto& values) {
      using T = typename std::decay_t<decltype(values)>::value_type;
      CHECK_MESSAGE(after.template channel<T>(info.name)[it->second] == values[p], info.name);
    });
    ++kept;
  }
  return kept;
}

}  // namespace

TEST_CASE_TEMPLATE("random rotations are proper rotations, reproducible by key", T, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = T::value;
  for (std::uint64_t key = 0; key < 50; ++key) {
    const Mat<dim> R = random_rotation<dim>(key);
    CHECK((R.transpose() * R - Mat<dim>::Identity()).norm() < tight);
    CHECK(R.determinant() == doctest::Approx(1.0).epsilon(tight));
    CHECK(R == random_rotation<dim>(key));
    CHECK((R - random_rotation<dim>(key + 1)).norm() > 1e-6);
  }
}

TEST_CASE_TEMPLATE("the deformation average", T, std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = T::value;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SUBCASE("equal matrices, inverted ones too, average to themselves") {
    for (int trial = 0; trial < 20; ++trial) {
      Mat<dim> F;
      for (int i = 0; i < dim; ++i)
        for (int j = 0; j < dim; ++j) F(i, j) = u(rng);
      const Mat<dim> A = average_deformation<dim>({F, F, F}, {0.2, 0.5, 0.3});
      CHECK((A - F).norm() < 1e-10 * F.norm());
    }
  }
  SUBCASE("rotations spread symmetrically about R0 average to R0") {
    const Mat<dim> R0 = random_rotation<dim>(3);
    for (double angle : {0.01, 0.3, 1.0}) {
      std::vector<Mat<dim>> F;
      for (int axis = 0; axis < (dim == 2 ? 1 : 3); ++axis)
        for (double sign : {-1.0, 1.0}) {
          Eigen::Matrix3d turn = Eigen::AngleAxisd(sign * angle, Eigen::Vector3d::Unit(dim == 2 ? 2 : axis)).matrix();
          F.push_back(R0 * turn.topLeftCorner<dim, dim>());
        }
      const Mat<dim> A = average_deformation<dim>(F, std::vector<double>(F.size(), 1.0));
      CHECK((A - R0).norm() < 1e-12);
    }
  }
  SUBCASE("commuting stretches average arithmetically") {
    const Mat<dim> R = random_rotation<dim>(11);
    const Vec<dim> s1 = Vec<dim>::LinSpaced(0.5, 1.5), s2 = Vec<dim>::LinSpaced(2.0, 1.2);
    const Mat<dim> A = average_deformation<dim>({R * s1.asDiagonal(), R * s2.asDiagonal()}, {1.0, 3.0});
    CHECK((A - R * Mat<dim>((0.25 * s1 + 0.75 * s2).asDiagonal())).norm() < 1e-12);
  }
  SUBCASE("near F = I, where U and V are not unique, the average stays near the mean") {
    // Averaging U and V separately would give an arbitrary rotation here; R S is within
    // O(eps^2) of the arithmetic mean.
    const double eps = 1e-4;
    std::vector<Mat<dim>> F;
    Mat<dim> mean = Mat<dim>::Zero();
    for (int i = 0; i < 8; ++i) {
      Mat<dim> E;
      for (int r = 0; r < dim; ++r)
        for (int c = 0; c < dim; ++c) E(r, c) = eps * u(rng);
      F.push_back(Mat<dim>::Identity() + E);
      mean += F.back() / 8.0;
    }
    CHECK((average_deformation<dim>(F, std::vector<double>(8, 1.0)) - mean).norm() < 10 * eps * eps);
  }
}

TEST_CASE_TEMPLATE("split and merge conserve mass and momentum", T, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = T::value;
  constexpr int children = 1 << dim;
  const CellTree<dim> tree = tree_of<dim>(3);
  const int k = 2;
  std::mt19937 rng(5);
  Particles<dim> P = solid_particles(tree);
  P.push_back(Vec<dim>::Constant(1.3), Vec<dim>::Zero(), 1.0, 1.0, 0);
  P.push_back(Vec<dim>::Constant(2.2), Vec<dim>::Zero(), 1.0, 1.0, 0);
  randomise(P, 0, rng);
  randomise(P, 1, rng);
  std::vector<std::uint16_t>& level = P.template channel<std::uint16_t>(kParticleLevel);
  level[0] = 1;
  level[1] = 0;
  const Particles<dim> before = P;

  SUBCASE("split") {
    const Totals t0 = totals(P);
    const Mat<dim> R = random_rotation<dim>(42);
    split_particle(P, 0, tree, k, R);
    REQUIRE(P.size() == 2 + children - 1);
    const Totals t1 = totals(P);
    CHECK(t1.mass == doctest::Approx(t0.mass).epsilon(tight));
    CHECK(t1.volume == doctest::Approx(t0.volume).epsilon(tight));
    CHECK((t1.momentum - t0.momentum).norm() < tight * t0.momentum.norm());
    CHECK((t1.moment - t0.moment).norm() < tight * t0.moment.norm());
    // The parent's affine spin becomes orbital: m eps:(C S), S = (b/4)^2 I, b = dx_1 / k.
    const double b = tree.dx(1) / k;
    const Eigen::Vector3d expected = t0.angular + before.mass[0] * (b / 4) * (b / 4) * spin<dim>(before.C[0]);
    CHECK((t1.angular - expected).norm() < tight * t0.angular.norm());
    const std::vector<Mat<dim>>& F = P.template channel<Mat<dim>>("F");
    for (std::size_t c : {std::size_t{0}, std::size_t{2}, std::size_t{3}}) {
      CHECK(level[c] == 2);
      CHECK(F[c] == before.template channel<Mat<dim>>("F")[0]);
      CHECK(P.C[c] == before.C[0]);
      CHECK(((P.x[c] - before.x[0]).array().abs() <= 0.5 * b * std::sqrt(double(dim)) / 2 + 1e-15).all());
    }
    CHECK(level[1] == 0);  // the other particle is untouched
    CHECK(P.x[1] == before.x[1]);

    SUBCASE("then merging the children restores the parent") {
      std::vector<std::size_t> group{0};
      for (std::size_t c = 2; c < P.size(); ++c) group.push_back(c);
      std::vector<std::uint8_t> erase(P.size(), 0);
      merge_particles(P, group, {"F"}, erase);
      P.erase_flagged(erase);
      REQUIRE(P.size() == 2);
      CHECK(level[0] == 1);
      CHECK((P.x[0] - before.x[0]).norm() < tight);
      CHECK((P.v[0] - before.v[0]).norm() < tight);
      CHECK((P.C[0] - before.C[0]).norm() < tight);
      CHECK(P.mass[0] == doctest::Approx(before.mass[0]).epsilon(tight));
      CHECK(P.volume0[0] == doctest::Approx(before.volume0[0]).epsilon(tight));
      CHECK((P.template channel<Mat<dim>>("F")[0] - before.template channel<Mat<dim>>("F")[0]).norm() < 1e-10);
      CHECK(P.template channel<double>("plastic")[0] ==
            doctest::Approx(before.template channel<double>("plastic")[0]).epsilon(tight));
    }
  }

  SUBCASE("merge of unrelated particles") {
    Particles<dim> Q = solid_particles(tree);
    std::uniform_real_distribution<double> u(1.0, 1.25);
    for (int i = 0; i < children; ++i) {
      Vec<dim> x;
      for (int a = 0; a < dim; ++a) x[a] = u(rng);
      Q.push_back(x, Vec<dim>::Zero(), 1.0, 1.0, 0);
      randomise(Q, Q.size() - 1, rng);
      Q.template channel<std::uint16_t>(kParticleLevel).back() = 2;
    }
    const Totals t0 = totals(Q);
    Eigen::Vector3d spread = Eigen::Vector3d::Zero();
    const Vec<dim> centre = t0.moment.head<dim>() / t0.mass, velocity = t0.momentum.head<dim>() / t0.mass;
    for (std::size_t p = 0; p < Q.size(); ++p) spread += Q.mass[p] * cross<dim>(Q.x[p] - centre, Q.v[p] - velocity);
    std::vector<std::size_t> group(Q.size());
    for (std::size_t p = 0; p < Q.size(); ++p) group[p] = p;
    std::vector<std::uint8_t> erase(Q.size(), 0);
    merge_particles(Q, group, {"F"}, erase);
    Q.erase_flagged(erase);
    REQUIRE(Q.size() == 1);
    const Totals t1 = totals(Q);
    CHECK(Q.template channel<std::uint16_t>(kParticleLevel)[0] == 1);
    CHECK(t1.mass == doctest::Approx(t0.mass).epsilon(tight));
    CHECK(t1.volume == doctest::Approx(t0.volume).epsilon(tight));
    CHECK((t1.momentum - t0.momentum).norm() < tight * t0.momentum.norm());
    CHECK((t1.moment - t0.moment).norm() < tight * t0.moment.norm());
    CHECK((t1.angular - (t0.angular - spread)).norm() < 1e-12 * (t0.angular.norm() + spread.norm()));
    CHECK(spread.norm() > 1e-3);  // the test would not see a dropped term of zero
  }
}

namespace {
// A box of particles of type `type` on their own lattice (k = 2 per axis per cell), at rest.
template <int dim>
Particles<dim> block(const CellTree<dim>& tree, int type, const Vec<dim>& lo, const Vec<dim>& hi) {
  Particles<dim> P = solid_particles(tree);
  const double h = tree.dx(type) / 2;
  IVec<dim> n;
  for (int a = 0; a < dim; ++a) n[a] = static_cast<int>(std::lround((hi[a] - lo[a]) / h));
  IVec<dim> i = IVec<dim>::Zero();
  while (true) {
    P.push_back(lo + h * (i.template cast<double>().array() + 0.5).matrix(), Vec<dim>::Zero(), std::pow(h, dim),
                std::pow(h, dim), 0);
    P.template channel<std::uint16_t>(kParticleLevel).back() = static_cast<std::uint16_t>(type);
    int a = 0;
    for (; a < dim; ++a) {
      if (++i[a] < n[a]) break;
      i[a] = 0;
    }
    if (a == dim) break;
  }
  return P;
}
}  // namespace

TEST_CASE_TEMPLATE("surface distance on the finest cells", T, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = T::value;
  const CellTree<dim> tree = tree_of<dim>(3, 4, 1.0);  // finest cells h = 0.25
  const double h = tree.dx(2);
  const Vec<dim> lo = Vec<dim>::Constant(1.0), hi = Vec<dim>::Constant(3.0);  // 8 finest cells per axis
  for (int type : {2, 1, 0}) {
    CAPTURE(type);
    const Particles<dim> P = block(tree, type, lo, hi);
    const auto& level = P.template channel<std::uint16_t>(kParticleLevel);
    const std::vector<double> d = surface_distance(tree, P.x, level, 2, 100.0);
    for (std::size_t p = 0; p < P.size(); ++p) {
      // The finest cell of the particle, its face steps to the block's outside.
      int steps = 1 << 20;
      for (int a = 0; a < dim; ++a) {
        const int c = static_cast<int>(std::floor((P.x[p][a] - lo[a]) / h));
        steps = std::min({steps, c + 1, 8 - c});
      }
      CHECK(d[p] == doctest::Approx((steps - 0.5) * h));
    }
    // Capped: cells deeper than the cap are reported beyond it.
    const std::vector<double> capped = surface_distance(tree, P.x, level, 2, 0.3);
    for (std::size_t p = 0; p < P.size(); ++p) CHECK((capped[p] == d[p] || (d[p] > 0.3 && capped[p] > 0.3)));
  }
}

TEST_CASE_TEMPLATE("resampling a block by the distance bands", T, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = T::value;
  const CellTree<dim> tree = tree_of<dim>(3, 4, 1.0);  // finest cells h = 0.25
  const double h = tree.dx(2);
  const Vec<dim> lo = Vec<dim>::Constant(1.0), hi = Vec<dim>::Constant(3.0);
  ResampleSettings s{0.5 * h, 1.2 * h, 1.6 * h, 1};

  SUBCASE("a fine block merges inside, keeps its fine surface band") {
    Particles<dim> P = block(tree, 2, lo, hi);
    std::mt19937 rng(3);
    for (std::size_t p = 0; p < P.size(); ++p) {
      const double V = P.volume0[p];  // nominal: merges need it
      randomise(P, p, rng);
      P.volume0[p] = V;
    }
    const Totals t0 = totals(P);
    const std::size_t n0 = P.size();
    const Particles<dim> copy = P;
    const ResampleCounts c = resample_particles(P, tree, 2, s, {"F"}, 0);
    CHECK(c.split == 0);
    CHECK(c.merged > 0);
    CHECK(P.size() == n0 - c.merged + c.groups);
    CHECK(untouched_particles_kept(copy, P) == n0 - c.merged);
    const Totals t1 = totals(P);
    CHECK(t1.mass == doctest::Approx(t0.mass).epsilon(tight));
    CHECK((t1.momentum - t0.momentum).norm() < 1e-12 * t0.mass);
    CHECK((t1.moment - t0.moment).norm() < 1e-12 * t0.moment.norm());
    // Only particles deeper than d_large merged: the outer two cell layers stay fine.
    const auto& level = P.template channel<std::uint16_t>(kParticleLevel);
    for (std::size_t p = 0; p < P.size(); ++p) {
      double depth = 1e300;
      for (int a = 0; a < dim; ++a) depth = std::min({depth, P.x[p][a] - lo[a], hi[a] - P.x[p][a]});
      if (depth < 2 * h) CHECK(level[p] == 2);
      if (depth > 2 * h + 0.25 * h) CHECK(level[p] == 1);
    }
    // Deterministic.
    Particles<dim> again = copy;
    resample_particles(again, tree, 2, s, {"F"}, 0);
    CHECK(again.x == P.x);
    CHECK(again.v == P.v);
  }

  SUBCASE("merges and splits in one call") {
    // A fine block merges inside while a coarse slab stored after it splits near the surface:
    // the merged-away particles are dropped and the children appended in one gather, the split
    // particles among those that move.
    Particles<dim> P = block(tree, 2, lo, hi);
    Vec<dim> slab_lo = lo, slab_hi = hi;
    slab_lo[0] = hi[0];
    slab_hi[0] = hi[0] + 2 * h;
    const Particles<dim> slab = block(tree, 1, slab_lo, slab_hi);
    const std::size_t fine = P.size();
    P.resize(fine + slab.size());
    P.for_each_channel([&](const ChannelInfo& info, auto& values) {
      const auto& from = *slab.template find_channel<typename std::decay_t<decltype(values)>::value_type>(info.name);
      std::copy(from.begin(), from.end(), values.begin() + static_cast<std::ptrdiff_t>(fine));
    });
    std::mt19937 rng(5);
    for (std::size_t p = 0; p < P.size(); ++p) {
      const double V = P.volume0[p];
      randomise(P, p, rng);
      P.volume0[p] = V;
    }
    const Totals t0 = totals(P);
    const std::size_t n0 = P.size();
    const Particles<dim> copy = P;
    const ResampleSettings bands{0.0, 1.55 * h, 1.6 * h, 1};  // the slab (d = h/2, 3h/2) splits
    const ResampleCounts c = resample_particles(P, tree, 2, bands, {"F"}, 0);
    CHECK(c.split > 0);
    CHECK(c.merged > 0);
    CHECK(P.size() == n0 - c.merged + c.groups + ((1 << dim) - 1) * c.split);
    CHECK(untouched_particles_kept(copy, P) == n0 - c.merged - c.split);
    const Totals t1 = totals(P);
    CHECK(t1.mass == doctest::Approx(t0.mass).epsilon(tight));
    CHECK(t1.volume == doctest::Approx(t0.volume).epsilon(tight));
    CHECK((t1.momentum - t0.momentum).norm() < 1e-12 * t0.mass);
    CHECK((t1.moment - t0.moment).norm() < 1e-12 * t0.moment.norm());
    Particles<dim> again = copy;
    resample_particles(again, tree, 2, bands, {"F"}, 0);
    CHECK(again.x == P.x);
    CHECK(again.mass == P.mass);
  }

  SUBCASE("a coarse block splits in the band, one level per resampling") {
    Particles<dim> P = block<dim>(tree, 0, Vec<dim>::Constant(0.0), Vec<dim>::Constant(4.0));
    const Totals t0 = totals(P);
    const ResampleCounts first = resample_particles(P, tree, 2, {0.0, 3.0 * h, 100.0, 1}, {"F"}, 1);
    CHECK(first.split > 0);
    CHECK(first.merged == 0);
    const auto& level = P.template channel<std::uint16_t>(kParticleLevel);
    int finest = 0;
    for (std::size_t p = 0; p < P.size(); ++p) finest = std::max<int>(finest, level[p]);
    CHECK(finest == 1);
    resample_particles(P, tree, 2, {0.0, 3.0 * h, 100.0, 1}, {"F"}, 2);
    for (std::size_t p = 0; p < P.size(); ++p) finest = std::max<int>(finest, level[p]);
    CHECK(finest == 2);
    const Totals t1 = totals(P);
    CHECK(t1.mass == doctest::Approx(t0.mass).epsilon(tight));
    CHECK((t1.moment - t0.moment).norm() < 1e-12 * t0.moment.norm());
  }

  SUBCASE("the guards: a lone coarse particle does not split, a lone fine one does not merge") {
    Particles<dim> P = solid_particles(tree);
    P.push_back(Vec<dim>::Constant(2.1), Vec<dim>::Zero(), 1.0, 1.0, 0);
    P.template channel<std::uint16_t>(kParticleLevel).back() = 0;
    CHECK(resample_particles(P, tree, 2, {0.0, 100.0, 200.0, 1}, {"F"}, 0).split == 0);
    P.template channel<std::uint16_t>(kParticleLevel).back() = 2;
    CHECK(resample_particles(P, tree, 2, {0.0, 1e-3, 2e-3, 1}, {"F"}, 0).merged == 0);
  }

  SUBCASE("the volume guard: half a coarse particle's volume does not merge") {
    // Deep inside a fine block, one coarse sub-cell (side h) loses two of its four particles:
    // they would merge into a half-weight coarse particle, which would split into four
    // half-weight fine ones, and so on.
    Particles<dim> P = block(tree, 2, lo, hi);
    const Vec<dim> centre = Vec<dim>::Constant(2.0 + 0.5 * h);  // the sub-cell [2, 2 + h)^dim
    std::vector<std::uint8_t> remove(P.size(), 0);
    int removed = 0;
    for (std::size_t p = 0; p < P.size(); ++p)
      if ((P.x[p] - centre).cwiseAbs().maxCoeff() < 0.5 * h && removed < (1 << dim) / 2) {
        remove[p] = 1;
        ++removed;
      }
    P.erase_flagged(remove);
    resample_particles(P, tree, 2, s, {"F"}, 0);
    const auto& level = P.template channel<std::uint16_t>(kParticleLevel);
    int fine_left = 0;
    for (std::size_t p = 0; p < P.size(); ++p)
      if ((P.x[p] - centre).cwiseAbs().maxCoeff() < 0.5 * h) fine_left += level[p] == 2;
    CHECK(fine_left == (1 << dim) / 2);
  }
}

TEST_CASE_TEMPLATE("Manhattan depth: the dense and the hashed search agree", T, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = T::value;
  // A cube of 6^dim sites (compact: the dense path), and the same cube beside a far copy (a
  // sparse set: the hashed path). Depth = 1 + the fewest steps to the cube's outside.
  std::vector<IVec<dim>> cube, pair;
  for (int i = 0; i < ipow(6, dim); ++i) {
    IVec<dim> c;
    for (int a = 0, r = i; a < dim; ++a, r /= 6) c[a] = r % 6 - 3;
    cube.push_back(c);
  }
  pair = cube;
  for (const IVec<dim>& c : cube) pair.push_back(c + IVec<dim>::Constant(5000));
  pair.push_back(cube[7]);  // a repeated site takes its first entry's depth
  const std::vector<int> dense = manhattan_depth(cube), hashed = manhattan_depth(pair);
  REQUIRE(hashed.size() == 2 * cube.size() + 1);
  for (std::size_t i = 0; i < cube.size(); ++i) {
    int steps = 1 << 20;
    for (int a = 0; a < dim; ++a) steps = std::min({steps, cube[i][a] + 3, 2 - cube[i][a]});
    CHECK(dense[i] == steps + 1);
    CHECK(hashed[i] == dense[i]);
    CHECK(hashed[cube.size() + i] == dense[i]);
  }
  CHECK(hashed.back() == dense[7]);
  const std::vector<int> capped = manhattan_depth(cube, 1);
  for (std::size_t i = 0; i < cube.size(); ++i) CHECK(capped[i] == std::min(dense[i], 2));

  // A random porous set (holes inside, a ragged outside): the dense transform's sweeps against
  // the hashed breadth-first search, site by site, uncapped and capped.
  std::mt19937 rng(7);
  std::vector<IVec<dim>> porous, porous_pair;
  for (int i = 0; i < ipow(12, dim); ++i) {
    IVec<dim> c;
    for (int a = 0, r = i; a < dim; ++a, r /= 12) c[a] = r % 12;
    if (std::uniform_real_distribution<double>(0, 1)(rng) < 0.85) porous.push_back(c);
  }
  porous_pair = porous;
  porous_pair.push_back(IVec<dim>::Constant(90000));  // far away: the hashed path
  for (int cap : {std::numeric_limits<int>::max() - 1, 2}) {
    const std::vector<int> swept = manhattan_depth(porous, cap), searched = manhattan_depth(porous_pair, cap);
    int deepest = 0;
    for (std::size_t i = 0; i < porous.size(); ++i) {
      CHECK(swept[i] == searched[i]);
      deepest = std::max(deepest, swept[i]);
    }
    CHECK(deepest >= 2);
  }
}

TEST_CASE(
    "the resample stage by travel: when the particles may have moved max_travel, at the same steps after a restart") {
  constexpr int dim = 2;
  const CellTree<dim> tree = tree_of<dim>(3, 4, 1.0);  // finest cells h = 0.25
  const double h = tree.dx(2);
  adaptive::ResampleSettings settings{0.5 * h, 1.2 * h, 1.6 * h, 1};
  settings.max_travel = 0.05;
  MpmState<dim> s;
  s.adaptive.emplace(tree, 2);
  s.particles = block<dim>(tree, 2, Vec<dim>::Constant(1.0), Vec<dim>::Constant(3.0));  // merges inside
  for (Vec<dim>& v : s.particles.v) v = Vec<dim>(-0.9, 1.2);  // 1.5 m/s: 0.015 m per step of 0.01 s
  stages::ResampleParticles<dim> stage(settings, {"F"});
  const auto resamplings = [](const stages::ResampleParticles<dim>& st) { return st.diagnostics()[2].value; };
  // Travel at the start of steps 0, 1, 2, ...: none yet (resample), 0.015, 0.030, 0.045, 0.060 >=
  // 0.05 (resample), ...: steps 0, 4 and 8 resample.
  const std::vector<double> expected{1, 1, 1, 1, 2, 2, 2, 2, 3, 3};
  std::optional<stages::ResampleParticles<dim>> restarted;
  MpmState<dim> restarted_state;
  for (int step = 0; step < 10; ++step) {
    s.step = step;
    s.dt = step == 0 ? 0.0 : 0.01;  // the last step's dt (none before the first)
    if (step == 6) {                // a restart here: the carried data and the state as a checkpoint holds them
      restarted.emplace(settings, std::vector<std::string>{"F"});
      restarted->restore(stage.carried());
      restarted_state.particles = s.particles;
      restarted_state.adaptive.emplace(tree, 2);
    }
    stage.run(s);
    CHECK_MESSAGE(resamplings(stage) == expected[step], "step ", step);
    if (restarted) {
      restarted_state.step = s.step;
      restarted_state.dt = s.dt;
      restarted->run(restarted_state);
      CHECK(resamplings(*restarted) == resamplings(stage));
      CHECK(restarted_state.particles.x == s.particles.x);
    }
  }
  CHECK(stage.diagnostics()[1].value > 0);  // the block did merge
}

TEST_CASE_TEMPLATE("walls: a body against a wall has no surface there, as if mirrored through it", T,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = T::value;
  // A cube of 6^dim sites [0, 5]^dim against walls before site 0 on axis 0 and after site 5 on
  // axis 1; without walls, its mirror image through both: sites [-6, 5] x [0, 11] x [0, 5].
  std::vector<IVec<dim>> cube, mirrored;
  for (int i = 0; i < ipow(12, dim); ++i) {
    IVec<dim> c;
    for (int a = 0, r = i; a < dim; ++a, r /= 12) c[a] = r % 12;
    if ((c.array() < 6).all()) cube.push_back(c);
    c[0] -= 6;
    if (dim == 2 || c[2] < 6) mirrored.push_back(c);
  }
  LatticeWalls<dim> walls;
  walls.lo[0] = 0;
  walls.hi[1] = 5;
  std::vector<IVec<dim>> pair = cube;  // the hashed path: a far copy along axis 0 makes the set sparse
  for (IVec<dim> c : cube) {
    c[0] += 50000;
    pair.push_back(c);
  }
  const std::vector<int> dense = manhattan_depth(cube, 1 << 20, walls), open = manhattan_depth(cube),
                         reference = manhattan_depth(mirrored), hashed = manhattan_depth(pair, 1 << 20, walls);
  int deeper = 0;
  for (std::size_t i = 0; i < cube.size(); ++i) {
    const auto at = std::find(mirrored.begin(), mirrored.end(), cube[i]) - mirrored.begin();
    CHECK(dense[i] == reference[static_cast<std::size_t>(at)]);
    CHECK(hashed[i] == dense[i]);
    CHECK(dense[i] >= open[i]);
    deeper += dense[i] > open[i];
  }
  CHECK(deeper > 0);

  // The domain's walls on a lattice: the material meets a wall `thickness` inside the face.
  Vec<dim> lo = Vec<dim>::Constant(-0.5), hi = Vec<dim>::Constant(10.5);
  geometry::DomainWalls<dim> domain(lo, hi, 0.5, geometry::Contact{geometry::ContactType::separate, 0.0});
  domain.set_wall(1, geometry::Side::lower, geometry::Contact{geometry::ContactType::sticky, 0.0});
  domain.set_wall(0, geometry::Side::upper, std::nullopt);  // open
  domain.set_wall(dim - 1, geometry::Side::upper, geometry::Contact{geometry::ContactType::separate, 0.3});
  const Vec<dim> origin = lo;  // the lattice from the domain's corner, h = 0.25: the walls at 2 and 42
  const LatticeWalls<dim> rough = lattice_walls(domain, SurfaceWalls::rough, origin, 0.25),
                          none = lattice_walls(domain, SurfaceWalls::none, origin, 0.25),
                          all = lattice_walls(domain, SurfaceWalls::all, origin, 0.25);
  constexpr int unbounded_lo = std::numeric_limits<int>::min(), unbounded_hi = std::numeric_limits<int>::max();
  CHECK(rough.lo[0] == 2);
  CHECK(rough.hi[0] == unbounded_hi);        // open
  CHECK(rough.lo[1] == unbounded_lo);        // sticky: a surface
  CHECK(rough.hi[dim - 1] == unbounded_hi);  // with friction: a surface
  if (dim == 3) CHECK(rough.hi[1] == 41);
  CHECK(none.lo[1] == 2);
  CHECK(none.hi[dim - 1] == 41);
  CHECK(none.hi[0] == unbounded_hi);
  CHECK((all.lo.array() == unbounded_lo).all());
  CHECK((all.hi.array() == unbounded_hi).all());
}
