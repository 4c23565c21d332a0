// bench_transfer: the particle <-> grid transfer benchmark of Gao et al. 2017 (adaptive GIMP,
// sec. 8 "Benchmark." and Table 1): particles on a lattice from 1/8 to 7/8 of the unit cube at
// spacing 1/256 (193^3 = 7.19 M particles), dx = 1/128, quadratic B-spline weights, APIC.
//
//   bench_transfer                                     (the paper's sizes, double and float)
//   bench_transfer --particles-spacing 0.0078125 --dx 0.015625 --repeat 1   (quick run)
//
// For each precision, input order (sorted by grid block / randomly shuffled) and thread count
// it prints the median seconds of the solver's transfers and of a textbook reference run in
// the same process: a dense uniform grid of (mass, momentum) and a plain loop over the
// particles in input order (single-threaded). The solver orders its own particles, so its
// timings include sort_into_buckets, reported separately ("sort") and summed ("step").
// Node normalisation v_i = (m v)_i / m_i is untimed on both sides. Before timing, the grids
// after P2G and the particles after G2P of both implementations are compared; the program
// exits 1 when they differ by more than round-off.
#include <mpm/core/transfer.h>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace mpm;

namespace {

template <class T> using V3 = Eigen::Matrix<T, 3, 1>;
template <class T> using M3 = Eigen::Matrix<T, 3, 3>;

struct Options {
  double spacing = 1.0 / 256;  //!< particle lattice spacing [m]
  double dx = 1.0 / 128;       //!< grid spacing [m]
  int repeat = 3;
  std::string precision = "both";
};

// 1. The benchmark particles: a lattice over [1/8, 7/8]^3 with reproducible pseudo-random
//    velocities and affine matrices (a transfer of a uniform field would hide errors).
Particles<3> lattice(const Options& o) {
  const int n = static_cast<int>(std::lround(0.75 / o.spacing)) + 1;
  const double mass = 1000.0 * o.spacing * o.spacing * o.spacing;  // water density [kg/m^3]
  std::mt19937_64 rng(2017);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles<3> P;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec<3> x = Vec<3>(i, j, k) * o.spacing + Vec<3>::Constant(0.125);
        P.push_back(x, Vec<3>(u(rng), u(rng), u(rng)), mass, mass / 1000.0, 0);
        for (int a = 0; a < 9; ++a) P.C.back().data()[a] = 10.0 * u(rng);
      }
  return P;
}

Particles<3> shuffled(const Particles<3>& P) {
  std::vector<std::uint32_t> order(P.size());
  for (std::size_t p = 0; p < order.size(); ++p) order[p] = static_cast<std::uint32_t>(p);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(42));
  Particles<3> out = P;
  out.permute(order);
  return out;
}

// 2. The reference: the textbook APIC transfer (Jiang et al. 2015) on a dense grid, one plain
//    loop over the particles in their input order, quadratic weights computed per particle.
template <class T>
struct ReferenceParticles {
  std::vector<V3<T>> x, v;
  std::vector<M3<T>> C;
  std::vector<T> mass;

  void assign(const Particles<3>& P) {
    x.resize(P.size());
    v.resize(P.size());
    C.resize(P.size());
    mass.resize(P.size());
    for (std::size_t p = 0; p < P.size(); ++p) {
      x[p] = P.x[p].cast<T>();
      v[p] = P.v[p].cast<T>();
      C[p] = P.C[p].cast<T>();
      mass[p] = static_cast<T>(P.mass[p]);
    }
  }
};

template <class T>
struct DenseGrid {
  struct Node {
    T mass = 0;
    V3<T> momentum = V3<T>::Zero();  // velocity after normalise()
  };
  int n;  // nodes per axis; node (i, j, k) at (i, j, k) dx
  T dx;
  std::vector<Node> nodes;

  DenseGrid(int nodes_per_axis, T spacing)
      : n(nodes_per_axis), dx(spacing), nodes(static_cast<std::size_t>(n) * n * n) {}
  Node& at(int i, int j, int k) { return nodes[(static_cast<std::size_t>(k) * n + j) * n + i]; }

  void normalise() {
    for (Node& g : nodes) g.momentum = g.mass > 0 ? V3<T>(g.momentum / g.mass) : V3<T>::Zero();
  }
};

// Quadratic B-spline weights of the 3 nodes base, base+1, base+2 on every axis.
template <class T>
struct QuadraticWeights {
  Eigen::Vector3i base;
  V3<T> fx;    // particle position minus base [cells]
  V3<T> w[3];  // w[node][axis]

  QuadraticWeights(const V3<T>& x, T inv_dx) {
    const V3<T> xi = x * inv_dx;
    base = (xi.array() - T(0.5)).floor().template cast<int>();
    fx = xi - base.template cast<T>();
    w[0] = T(0.5) * (T(1.5) - fx.array()).square();
    w[1] = T(0.75) - (fx.array() - T(1)).square();
    w[2] = T(0.5) * (fx.array() - T(0.5)).square();
  }
};

template <class T>
void reference_p2g(const ReferenceParticles<T>& P, DenseGrid<T>& grid) {
  std::fill(grid.nodes.begin(), grid.nodes.end(), typename DenseGrid<T>::Node{});
  const T inv_dx = 1 / grid.dx;
  for (std::size_t p = 0; p < P.x.size(); ++p) {
    const QuadraticWeights<T> q(P.x[p], inv_dx);
    const T m = P.mass[p];
    const V3<T> mv = m * P.v[p];
    const M3<T> affine = m * P.C[p];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          const V3<T> dpos = (V3<T>(i, j, k) - q.fx) * grid.dx;
          const T weight = q.w[i][0] * q.w[j][1] * q.w[k][2];
          auto& node = grid.at(q.base[0] + i, q.base[1] + j, q.base[2] + k);
          node.mass += weight * m;
          node.momentum += weight * (mv + affine * dpos);
        }
  }
}

template <class T>
void reference_g2p(ReferenceParticles<T>& P, DenseGrid<T>& grid, T dt) {
  const T inv_dx = 1 / grid.dx;
  const T inv_D = 4 * inv_dx * inv_dx;  // APIC D_p^-1 for quadratic weights
  for (std::size_t p = 0; p < P.x.size(); ++p) {
    const QuadraticWeights<T> q(P.x[p], inv_dx);
    V3<T> v = V3<T>::Zero();
    M3<T> B = M3<T>::Zero();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          const V3<T> dpos = (V3<T>(i, j, k) - q.fx) * grid.dx;
          const T weight = q.w[i][0] * q.w[j][1] * q.w[k][2];
          const V3<T>& vi = grid.at(q.base[0] + i, q.base[1] + j, q.base[2] + k).momentum;
          v += weight * vi;
          B += (weight * vi) * dpos.transpose();
        }
    P.v[p] = v;
    P.C[p] = B * inv_D;
    P.x[p] += dt * v;
  }
}

// 3. Timing: median over repeats, each from a fresh copy of the input (copy untimed).
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

struct Timings {
  double sort = 0, p2g = 0, g2p = 0;
};

Timings median(const std::vector<Timings>& runs) {
  std::vector<double> s, p, g;
  for (const Timings& t : runs) {
    s.push_back(t.sort);
    p.push_back(t.p2g);
    g.push_back(t.g2p);
  }
  return {median(s), median(p), median(g)};
}

constexpr double dt = 1e-4;  // [s]; G2P advects x by dt v

struct Setup {
  Kernel kernel = QuadraticBSpline{};
  TransferScheme scheme;  // APIC
  SparseGrid<3> grid;
  int nodes_per_axis;
  explicit Setup(double dx)
      : grid(Vec<3>::Zero(), Vec<3>::Ones(), dx),
        nodes_per_axis(static_cast<int>(std::lround(1.0 / dx)) + 1) {}
};

Timings time_library(const Particles<3>& input, Setup& s, Particles<3>& P, ParticleBuckets<3>& buckets) {
  P = input;
  Timings t;
  auto t0 = Clock::now();
  sort_into_buckets(P, s.kernel, s.grid, buckets);
  t.sort = seconds_since(t0);
  t0 = Clock::now();
  particles_to_grid(P, buckets, s.kernel, s.scheme, s.grid);
  t.p2g = seconds_since(t0);
  momentum_to_velocity(s.grid, s.scheme);
  t0 = Clock::now();
  grid_to_particles(P, buckets, s.kernel, s.scheme, s.grid, dt);
  t.g2p = seconds_since(t0);
  return t;
}

template <class T>
Timings time_reference(const Particles<3>& input, DenseGrid<T>& grid, ReferenceParticles<T>& P) {
  P.assign(input);
  Timings t;
  auto t0 = Clock::now();
  reference_p2g(P, grid);
  t.p2g = seconds_since(t0);
  grid.normalise();
  t0 = Clock::now();
  reference_g2p(P, grid, static_cast<T>(dt));
  t.g2p = seconds_since(t0);
  return t;
}

// 4. Correctness: both implementations from the same particles. Differences are relative to
//    the largest magnitude of the quantity (node values near zero make pointwise ratios moot).
struct Deviation {
  double mass = 0, momentum = 0, v = 0, C = 0;
  double max() const { return std::max({mass, momentum, v, C}); }
};

template <class T>
Deviation compare_library(const Particles<3>& input, Setup& s) {
  Particles<3> P = input;
  ParticleBuckets<3> buckets;
  sort_into_buckets(P, s.kernel, s.grid, buckets);
  particles_to_grid(P, buckets, s.kernel, s.scheme, s.grid);
  ReferenceParticles<T> R;
  R.assign(P);
  DenseGrid<T> dense(s.nodes_per_axis, static_cast<T>(s.grid.dx()));
  reference_p2g(R, dense);

  Deviation d;
  double scale_m = 0, scale_p = 0, err_m = 0, err_p = 0, total_sparse = 0, total_dense = 0;
  for (std::size_t k = 0; k < s.grid.node_storage(); ++k) {
    const IVec<3> c = s.grid.node_coord(k);
    if ((c.array() >= s.nodes_per_axis).any()) continue;  // block padding beyond the domain
    const auto& node = dense.at(c[0], c[1], c[2]);
    err_m = std::max(err_m, std::abs(s.grid.mass[k] - node.mass));
    err_p = std::max(err_p, (s.grid.velocity[k] - node.momentum.template cast<double>()).norm());
    total_sparse += s.grid.mass[k];
  }
  for (const auto& node : dense.nodes) {
    scale_m = std::max(scale_m, static_cast<double>(node.mass));
    scale_p = std::max(scale_p, static_cast<double>(node.momentum.norm()));
    total_dense += node.mass;
  }
  d.mass = std::max(err_m / scale_m, std::abs(total_sparse - total_dense) / total_dense);
  d.momentum = err_p / scale_p;

  momentum_to_velocity(s.grid, s.scheme);
  dense.normalise();
  grid_to_particles(P, buckets, s.kernel, s.scheme, s.grid, dt);
  reference_g2p(R, dense, static_cast<T>(dt));
  double scale_v = 0, scale_C = 0, err_v = 0, err_C = 0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    scale_v = std::max(scale_v, static_cast<double>(R.v[p].norm()));
    scale_C = std::max(scale_C, static_cast<double>(R.C[p].norm()));
    err_v = std::max(err_v, (P.v[p] - R.v[p].template cast<double>()).norm());
    err_C = std::max(err_C, (P.C[p] - R.C[p].template cast<double>()).norm());
  }
  d.v = err_v / scale_v;
  d.C = err_C / scale_C;
  return d;
}

// 5. One precision: correctness check, then the timings for both input orders.
struct Row {
  std::string order;
  int threads;
  Timings optimised, reference;
};

template <class T>
bool run_precision(const Options& o, const char* name, const Particles<3>& sorted_input) {
  Setup s(o.dx);
  const Particles<3> shuffled_input = shuffled(sorted_input);
  const double tolerance = sizeof(T) == 8 ? 1e-10 : 1e-4;
  const Deviation d = compare_library<T>(sorted_input, s);
  std::printf("%s: solver vs reference, max relative difference: node mass %.2e, momentum %.2e, "
              "particle v %.2e, C %.2e (tolerance %.0e) %s\n",
              name, d.mass, d.momentum, d.v, d.C, tolerance, d.max() < tolerance ? "ok" : "FAILED");
  if (!(d.max() < tolerance)) return false;

  std::vector<Row> rows;
  Particles<3> work;
  ParticleBuckets<3> buckets;
  ReferenceParticles<T> ref_work;
  DenseGrid<T> dense(s.nodes_per_axis, static_cast<T>(o.dx));
  for (const auto& [order, input] : {std::pair<std::string, const Particles<3>*>{"sorted", &sorted_input},
                                     {"shuffled", &shuffled_input}}) {
    std::vector<Timings> ref;
    for (int r = 0; r < o.repeat; ++r) ref.push_back(time_reference(*input, dense, ref_work));
    for (int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      std::vector<Timings> opt;
      for (int r = 0; r < o.repeat; ++r) opt.push_back(time_library(*input, s, work, buckets));
      rows.push_back({order, threads, median(opt), median(ref)});
    }
  }

  std::printf("\n%s precision, %zu particles, dx = %g, median of %d (seconds; reference is "
              "single-threaded)\n", name, sorted_input.size(), o.dx, o.repeat);
  std::printf("%-9s %3s | %7s %7s %7s %7s | %7s %7s | %9s %9s\n", "order", "thr", "sort", "P2G",
              "G2P", "step", "ref P2G", "ref G2P", "P2G x", "G2P x");
  for (const Row& r : rows) {
    const Timings& t = r.optimised;
    std::printf("%-9s %3d | %7.3f %7.3f %7.3f %7.3f | %7.3f %7.3f | %9.2f %9.2f\n", r.order.c_str(),
                r.threads, t.sort, t.p2g, t.g2p, t.sort + t.p2g + t.g2p, r.reference.p2g,
                r.reference.g2p, r.reference.p2g / t.p2g, r.reference.g2p / t.g2p);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"Particle <-> grid transfer benchmark (Gao et al. 2017, Table 1)"};
  app.add_option("--particles-spacing", o.spacing, "particle lattice spacing [m]")
      ->check(CLI::Range(1e-4, 0.25));
  app.add_option("--dx", o.dx, "grid spacing [m]")->check(CLI::Range(1e-3, 0.25));
  app.add_option("--repeat", o.repeat, "timed repetitions (median reported)")->check(CLI::Range(1, 100));
  app.add_option("--precision", o.precision)->check(CLI::IsMember({"float", "double", "both"}));
  CLI11_PARSE(app, argc, argv);

  Particles<3> input = lattice(o);
  {  // "sorted" is the solver's own order, as after its first step
    SparseGrid<3> grid(Vec<3>::Zero(), Vec<3>::Ones(), o.dx);
    ParticleBuckets<3> buckets;
    sort_into_buckets(input, Kernel{QuadraticBSpline{}}, grid, buckets);
  }
  bool ok = true;
  if (o.precision != "float") ok = run_precision<double>(o, "double", input) && ok;
  if (o.precision != "double") ok = run_precision<float>(o, "float", input) && ok;
  return ok ? 0 : 1;
}
