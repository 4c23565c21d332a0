// The bucket order is an index over the particle storage: every bucket holds exactly the
// particles whose first stencil node lies in its block, scattered storage is moved into
// bucket order once, nearly ordered storage is reached through the index with transfers
// bitwise equal to those on moved particles, single-precision positions give the same
// buckets, and the scalar-generic loops run in float. The parallel key sort under the buckets
// equals std::stable_sort. The patch nodes the loops copy are those the stencils can reach.
#include <mpm/core/block_table.h>
#include <mpm/core/detail/transfer_loops.h>
#include <mpm/core/error.h>
#include <mpm/core/transfer.h>

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include "random_particles.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

using namespace mpm;

namespace {
using test::random_cloud;

// Every particle sits in the bucket of its block, each exactly once, buckets in block order.
template <int dim>
void check_buckets(const Particles<dim>& P, const Kernel& kernel, const SparseGrid<dim>& grid,
                   const ParticleBuckets<dim>& b) {
  std::vector<std::uint32_t> seen = b.particle;
  std::sort(seen.begin(), seen.end());
  std::vector<std::uint32_t> all(P.size());
  std::iota(all.begin(), all.end(), 0u);
  REQUIRE(seen == all);
  REQUIRE(b.begin.size() == b.block.size() + 1);
  for (int k = 0; k < b.count(); ++k) {
    if (k > 0) REQUIRE(b.block[k - 1] < b.block[k]);
    for (std::uint32_t i = b.begin[k]; i < b.begin[k + 1]; ++i)
      REQUIRE(grid.block_id(stencil_base(grid, kernel, P.x[b.particle[i]])) == b.block[k]);
  }
}

template <int dim>
void check_storage_orders() {
  CAPTURE(dim);
  const Kernel kernel = QuadraticBSpline{};
  SparseGrid<dim> grid(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 32);
  ParticleBuckets<dim> buckets;
  Particles<dim> P =
      random_cloud<dim>(20000, Vec<dim>::Constant(0.2), Vec<dim>::Constant(0.8), 11);  // random storage: scattered
  CHECK(sort_into_buckets(P, kernel, grid, buckets));
  for (std::size_t i = 0; i < P.size(); ++i) REQUIRE(buckets.particle[i] == i);
  check_buckets(P, kernel, grid, buckets);
  CHECK_FALSE(sort_into_buckets(P, kernel, grid, buckets));  // already in order: nothing moves

  // A few particles change buckets: the storage stays, the index takes them elsewhere.
  for (std::size_t p = 0; p < P.size(); p += 97) P.x[p][0] = std::min(0.8, P.x[p][0] + 0.2);
  Particles<dim> Q = P;
  CHECK_FALSE(sort_into_buckets(P, kernel, grid, buckets));
  check_buckets(P, kernel, grid, buckets);
  std::size_t out_of_place = 0;
  for (std::size_t i = 0; i < P.size(); ++i) out_of_place += buckets.particle[i] != i;
  CHECK(out_of_place > 0);

  // The same particles stored in bucket order give bitwise the same transfers.
  const TransferScheme apic;
  particles_to_grid(P, buckets, kernel, apic, grid);
  const std::vector<double> mass = grid.mass;
  const std::vector<Vec<dim>> momentum = grid.velocity;
  momentum_to_velocity(grid, apic);
  grid_to_particles(P, buckets, kernel, apic, grid, 1e-3);

  ParticleBuckets<dim> moved;
  SparseGrid<dim> grid2(Vec<dim>::Zero(), Vec<dim>::Ones(), 1.0 / 32);
  Q.permute(bucket_order<dim, double>(Q.x, kernel, grid2, moved));
  particles_to_grid(Q, moved, kernel, apic, grid2);
  CHECK(grid2.mass == mass);
  CHECK(grid2.velocity == momentum);
  momentum_to_velocity(grid2, apic);
  grid_to_particles(Q, moved, kernel, apic, grid2, 1e-3);
  for (std::size_t i = 0; i < P.size(); ++i) {
    const std::uint32_t p = buckets.particle[i];
    REQUIRE(Q.x[i] == P.x[p]);
    REQUIRE(Q.v[i] == P.v[p]);
    REQUIRE(Q.C[i] == P.C[p]);
  }
}
}  // namespace

TEST_CASE("buckets index the particles; scattered storage is moved once, nearly ordered is not") {
  check_storage_orders<2>();
  check_storage_orders<3>();
}

TEST_CASE("single-precision positions give the same buckets and a float P2G agrees") {
  const QuadraticBSpline kernel;
  // Dyadic positions (a lattice of spacing dx/4) are exact in float, so both precisions see
  // the same stencils.
  Particles<3> P;
  for (int k = 0; k < 24; ++k)
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 24; ++i)
        P.push_back(Vec<3>(i, j, k) / 128.0 + Vec<3>::Constant(0.25), Vec<3>(i, -j, 0.5 * k), 1e-3, 1e-6, 0);
  SparseGrid<3> grid(Vec<3>::Zero(), Vec<3>::Ones(), 1.0 / 32);
  ParticleBuckets<3> buckets;
  sort_into_buckets(P, kernel, grid, buckets);

  struct FloatParticles {
    std::vector<Eigen::Vector3f> x, v;
    std::vector<Eigen::Matrix3f> C;
    std::vector<float> mass;
  } F;
  for (std::size_t p = 0; p < P.size(); ++p) {
    F.x.push_back(P.x[p].cast<float>());
    F.v.push_back(P.v[p].cast<float>());
    F.C.push_back(Eigen::Matrix3f::Zero());
    F.mass.push_back(static_cast<float>(P.mass[p]));
  }
  SparseGrid<3> grid_f(Vec<3>::Zero(), Vec<3>::Ones(), 1.0 / 32);
  ParticleBuckets<3> buckets_f;
  sort_into_buckets<3, float>(F.x, Kernel{kernel}, grid_f, buckets_f);
  CHECK(buckets_f.particle == buckets.particle);
  CHECK(buckets_f.begin == buckets.begin);
  CHECK(buckets_f.block == buckets.block);

  particles_to_grid(P, buckets, Kernel{kernel}, TransferScheme{}, grid);
  std::vector<float> mass(grid_f.node_storage(), 0.0f);
  std::vector<Eigen::Vector3f> momentum(grid_f.node_storage(), Eigen::Vector3f::Zero());
  std::array<detail::BasicChannelView<float>, 4> channels{detail::scalar_view(mass)};
  for (int a = 0; a < 3; ++a) channels[a + 1] = detail::component_view<3>(momentum, a);
  detail::p2g<3, QuadraticBSpline, true>(F, buckets_f, kernel, grid_f, channels);
  double err = 0, scale = 0;
  for (std::size_t k = 0; k < grid.node_storage(); ++k) {
    err = std::max(err, (momentum[k].cast<double>() - grid.velocity[k]).norm());
    scale = std::max(scale, grid.velocity[k].norm());
  }
  CHECK(err < 1e-5 * scale);
}

TEST_CASE("the lowest-indexed bad particle is reported, whatever the thread count") {
  SparseGrid<3> grid(Vec<3>::Zero(), Vec<3>::Ones(), 1.0 / 32);
  Particles<3> P = random_cloud<3>(100000, Vec<3>::Constant(0.2), Vec<3>::Constant(0.8), 5);
  P.x[70000] = Vec<3>(2.0, 0.5, 0.5);
  P.x[12345] = Vec<3>(0.5, std::nan(""), 0.5);
  ParticleBuckets<3> buckets;
  CHECK_THROWS_WITH_AS(sort_into_buckets(P, Kernel{QuadraticBSpline{}}, grid, buckets, "sort"),
                       doctest::Contains("particle 12345 has a non-finite position"), NumericalError);
}

TEST_CASE("the parallel key sort equals std::stable_sort on every thread count") {
  // Keys in runs (particles of one block side by side), then shuffled, then sorted; several
  // chunks of 2^16 keys (their number set by the thread count at 700 000 keys), few and many
  // distinct keys, and the empty and sorted cases.
  std::mt19937_64 random(5);
  for (const std::size_t n :
       {std::size_t{0}, std::size_t{1}, std::size_t{1000}, std::size_t{300000}, std::size_t{700000}}) {
    for (const BlockKey distinct : {BlockKey{3}, BlockKey{5000}}) {
      std::vector<BlockKey> runs;
      while (runs.size() < n) runs.insert(runs.end(), 1 + random() % 40, (random() % distinct) * 7919);
      runs.resize(n);
      std::vector<BlockKey> shuffled = runs, sorted = runs;
      std::shuffle(shuffled.begin(), shuffled.end(), random);
      std::sort(sorted.begin(), sorted.end());
      for (const std::vector<BlockKey>* keys : {&runs, &shuffled, &sorted}) {
        std::vector<std::uint32_t> expected(n);
        std::iota(expected.begin(), expected.end(), std::uint32_t{0});
        std::stable_sort(expected.begin(), expected.end(),
                         [&](std::uint32_t a, std::uint32_t b) { return (*keys)[a] < (*keys)[b]; });
        for (const int threads : {1, 2, 7}) {
          CAPTURE(n);
          CAPTURE(threads);
          tbb::task_arena arena(threads);
          const KeyOrder got = arena.execute([&] { return sort_keys(*keys); });
          CHECK(got.identity == (keys == &sorted || std::is_sorted(keys->begin(), keys->end())));
          CHECK((got.identity ? got.order.empty() : got.order == expected));
          CHECK(stable_key_order(*keys) == expected);
          // The distinct keys ascending, each beginning where the sorted sequence reaches it.
          REQUIRE(got.begin.size() == got.key.size() + 1);
          CHECK(got.begin.back() == n);
          bool runs_match = true;
          for (std::size_t r = 0; r < got.key.size(); ++r) {
            runs_match = runs_match && got.begin[r] < got.begin[r + 1] && (*keys)[expected[got.begin[r]]] == got.key[r];
            if (got.begin[r] > 0) runs_match = runs_match && (*keys)[expected[got.begin[r] - 1]] < got.key[r];
          }
          CHECK(runs_match);
        }
      }
    }
  }
}

namespace {
// Every node of every stencil that starts in the bucket's block is in the patch's reach, and
// the reach holds no other node: (B + support - 1)^dim nodes, each once, each at its storage
// place in its corner block.
template <int dim, int support>
void check_patch_reach() {
  constexpr int B = SparseGrid<dim>::block_size, W = detail::patch_width<dim>;
  constexpr const detail::PatchReach<dim, support>& reach = detail::patch_reach<dim, support>;
  std::vector<int> listed(detail::patch_nodes<dim>, 0);
  for (int corner = 0; corner < (1 << dim); ++corner)
    for (int i = 0; i < reach.count[corner]; ++i) {
      const int patch = reach.patch[corner][i], local = reach.local[corner][i];
      ++listed[static_cast<std::size_t>(patch)];
      for (int a = 0, p = patch, l = local; a < dim; ++a, p /= W, l /= B)
        CHECK(p % W == l % B + ((corner >> a) & 1) * B);
    }
  int reached = 0;
  for (int patch = 0; patch < detail::patch_nodes<dim>; ++patch) {
    bool in_stencil = true;  // some stencil starting in [0, B) per axis holds it
    for (int a = 0, p = patch; a < dim; ++a, p /= W) in_stencil = in_stencil && p % W < B + support - 1;
    CHECK(listed[static_cast<std::size_t>(patch)] == (in_stencil ? 1 : 0));
    reached += in_stencil;
  }
  CHECK(reached == ipow(B + support - 1, dim));
}
}  // namespace

TEST_CASE("the patch nodes copied are exactly those the stencils reach") {
  check_patch_reach<2, 3>();
  check_patch_reach<2, 4>();
  check_patch_reach<3, 3>();
  check_patch_reach<3, 4>();
}
