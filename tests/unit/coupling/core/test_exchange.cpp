#include <coupling/momentum_exchange.h>
#include <doctest/doctest.h>
#include <mpm/core/error.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

using coupling::exchange_node;
using mpm::Vec;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kStiffness[] = {0.0, 1e-6, 1e-2, 1.0, 1e3, 1e8, 1e30, kInf};

struct NodeState {
  double m_w, m_s;
  Vec<3> v_w, v_s;
};

std::vector<NodeState> random_nodes(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> mass(1e-6, 10.0), speed(-3.0, 3.0);
  std::vector<NodeState> nodes;
  for (int i = 0; i < n; ++i)
    nodes.push_back(
        {mass(rng), mass(rng), Vec<3>(speed(rng), speed(rng), speed(rng)), Vec<3>(speed(rng), speed(rng), speed(rng))});
  return nodes;
}

}  // namespace

TEST_CASE("exchange_node: momentum to round-off and the closed-form slip decay for any K") {
  for (const NodeState& s : random_nodes(200)) {
    const Vec<3> momentum = s.m_w * s.v_w + s.m_s * s.v_s;
    const double scale = s.m_w * s.v_w.norm() + s.m_s * s.v_s.norm();
    const double slip = (s.v_s - s.v_w).norm();
    for (const double K : kStiffness) {
      CAPTURE(K);
      Vec<3> v_w = s.v_w, v_s = s.v_s;
      exchange_node<3>(s.m_w, s.m_s, K, v_w, v_s);
      REQUIRE(v_w.allFinite());
      REQUIRE(v_s.allFinite());
      CHECK((s.m_w * v_w + s.m_s * v_s - momentum).norm() <= 4e-16 * scale);
      const double expected = slip / (1.0 + K * (1.0 / s.m_w + 1.0 / s.m_s));  // 0 for K = inf
      CHECK(std::abs((v_s - v_w).norm() - expected) <= 1e-14 * slip);
      CHECK((v_s - v_w).norm() <= slip * (1.0 + 1e-15));
    }
  }
}

TEST_CASE("exchange_node solves the backward-Euler equations; K -> inf gives the common velocity") {
  for (const NodeState& s : random_nodes(100)) {
    const double scale = s.m_w * s.v_w.norm() + s.m_s * s.v_s.norm();
    for (const double K : {0.0, 0.3, 5.0, 40.0}) {
      Vec<3> v_w = s.v_w, v_s = s.v_s;
      exchange_node<3>(s.m_w, s.m_s, K, v_w, v_s);
      // m_w (v_w' - v_w) = K (v_s' - v_w'),  m_s (v_s' - v_s) = K (v_w' - v_s')
      CHECK((s.m_w * (v_w - s.v_w) - K * (v_s - v_w)).norm() <= 1e-14 * (1.0 + K) * scale);
      CHECK((s.m_s * (v_s - s.v_s) - K * (v_w - v_s)).norm() <= 1e-14 * (1.0 + K) * scale);
    }
    const Vec<3> common = (s.m_w * s.v_w + s.m_s * s.v_s) / (s.m_w + s.m_s);
    for (const double K : {1e30, kInf}) {
      Vec<3> v_w = s.v_w, v_s = s.v_s;
      exchange_node<3>(s.m_w, s.m_s, K, v_w, v_s);
      CHECK((v_w - common).norm() <= 1e-14 * (1.0 + common.norm()) + 1e-20 * scale);
      CHECK((v_s - common).norm() <= 1e-14 * (1.0 + common.norm()) + 1e-20 * scale);
    }
  }
}

TEST_CASE("a node with one phase is unchanged") {
  for (const double K : kStiffness) {
    Vec<2> v_w(1.0, -2.0), v_s(-0.5, 3.0);
    exchange_node<2>(0.0, 2.0, K, v_w, v_s);
    CHECK(v_w == Vec<2>(1.0, -2.0));
    CHECK(v_s == Vec<2>(-0.5, 3.0));
    exchange_node<2>(2.0, 0.0, K, v_w, v_s);
    CHECK(v_w == Vec<2>(1.0, -2.0));
    CHECK(v_s == Vec<2>(-0.5, 3.0));
  }
}

TEST_CASE("exchange_momentum over node arrays equals exchange_node per node") {
  const std::vector<NodeState> nodes = random_nodes(10000);
  std::vector<double> m_w, m_s, K;
  std::vector<Vec<3>> v_w, v_s;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    m_w.push_back(i % 7 == 0 ? 0.0 : nodes[i].m_w);
    m_s.push_back(nodes[i].m_s);
    v_w.push_back(nodes[i].v_w);
    v_s.push_back(nodes[i].v_s);
    K.push_back(std::pow(10.0, static_cast<double>(i % 41) - 20.0));
  }
  std::vector<Vec<3>> w = v_w, s = v_s;
  coupling::exchange_momentum<3>(m_w, w, m_s, s, K);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    exchange_node<3>(m_w[i], m_s[i], K[i], v_w[i], v_s[i]);
    REQUIRE(w[i] == v_w[i]);
    REQUIRE(s[i] == v_s[i]);
  }
  K.pop_back();
  CHECK_THROWS_AS(coupling::exchange_momentum<3>(m_w, w, m_s, s, K), mpm::InputError);
}

TEST_CASE("MomentumExchange on two grids with different allocated blocks") {
  using Grid = mpm::SparseGrid<2>;
  const double dx = 0.01, dt = 1e-3;
  Grid fluid(Vec<2>::Zero(), Vec<2>::Constant(0.3), dx), sediment(Vec<2>::Zero(), Vec<2>::Constant(0.3), dx);
  // Blocks 0 and 1 in the fluid, blocks 1 and 2 in the sediment (storage orders differ).
  fluid.activate({0, 1});
  sediment.activate({1, 2});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> mass(0.1, 1.0), speed(-1.0, 1.0);
  for (std::size_t k = 0; k < fluid.node_storage(); ++k) {
    fluid.mass[k] = mass(rng);
    fluid.velocity[k] = Vec<2>(speed(rng), speed(rng));
  }
  for (std::size_t k = 0; k < sediment.node_storage(); ++k) {
    sediment.mass[k] = k % 5 == 0 ? 0.0 : mass(rng);
    sediment.velocity[k] = Vec<2>(speed(rng), speed(rng));
  }
  std::vector<double> n_w(sediment.node_storage());
  for (std::size_t k = 0; k < n_w.size(); ++k) n_w[k] = 0.4 + 0.6 * static_cast<double>(k % 11) / 10.0;

  const auto total = [](const Grid& g) {
    Vec<2> p = Vec<2>::Zero();
    for (std::size_t k = 0; k < g.node_storage(); ++k) p += g.mass[k] * g.velocity[k];
    return p;
  };
  const Vec<2> before = total(fluid) + total(sediment);
  const Grid fluid0 = fluid, sediment0 = sediment;
  const coupling::drag::DragLaw law = coupling::drag::Gidaspow{{2e-4, 1e-3, 1000.0}};
  std::vector<double> beta;  // the step's coefficients, for the mixture projection
  coupling::MomentumExchange<2>(law).apply(fluid, sediment, n_w, dt, beta);
  CHECK((total(fluid) + total(sediment) - before).norm() <= 1e-14 * 64.0);
  REQUIRE(beta.size() == sediment.node_storage());

  int exchanged = 0;
  for (std::size_t ks = 0; ks < sediment.node_storage(); ++ks) {
    const mpm::Index kw = fluid.node_index(sediment.node_coord(ks));
    if (kw < 0) {  // block 2: sediment only
      CHECK(sediment.velocity[ks] == sediment0.velocity[ks]);
      CHECK(beta[ks] == 0.0);
      continue;
    }
    const auto w = static_cast<std::size_t>(kw);
    Vec<2> v_w = fluid0.velocity[w], v_s = sediment0.velocity[ks];
    // beta at the slip entering the exchange (not the relaxed slip it leaves).
    CHECK(beta[ks] == coupling::drag::beta(law, n_w[ks], (v_s - v_w).norm()));
    const double K = beta[ks] * dx * dx * dt;
    exchange_node<2>(fluid0.mass[w], sediment0.mass[ks], K, v_w, v_s);
    CHECK((fluid.velocity[w] - v_w).norm() <= 1e-14);
    CHECK((sediment.velocity[ks] - v_s).norm() <= 1e-14);
    const double slip = (sediment.velocity[ks] - fluid.velocity[w]).norm();
    const double slip0 = (sediment0.velocity[ks] - fluid0.velocity[w]).norm();
    if (sediment0.mass[ks] > 0.0 && n_w[ks] < 1.0) {
      ++exchanged;
      CHECK(slip < slip0);
    } else {  // one phase, or no sediment volume (beta = 0)
      CHECK(slip == doctest::Approx(slip0).epsilon(1e-15));
    }
  }
  CHECK(exchanged > 40);
  for (std::size_t kw = 0; kw < Grid::nodes_per_block; ++kw)  // block 0: fluid only
    CHECK(fluid.velocity[kw] == fluid0.velocity[kw]);

  Grid other(Vec<2>::Zero(), Vec<2>::Constant(0.3), 2 * dx);
  other.activate({0});
  CHECK_THROWS_AS(coupling::MomentumExchange<2>(law).apply(other, sediment, n_w, dt, beta), mpm::InputError);
  n_w.pop_back();
  CHECK_THROWS_AS(coupling::MomentumExchange<2>(law).apply(fluid, sediment, n_w, dt, beta), mpm::InputError);
}
