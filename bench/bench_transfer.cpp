// bench_transfer: the particle <-> grid transfer benchmark of Gao et al. 2017 (adaptive GIMP,
// sec. 8 "Benchmark." and Table 1): particles on a lattice from 1/8 to 7/8 of the unit cube at
// spacing 1/256 (193^3 = 7.19 M particles), dx = 1/128, quadratic B-spline weights, APIC.
//
//   bench_transfer                                     (the paper's sizes, double and float)
//   bench_transfer --particles-spacing 0.0078125 --dx 0.015625 --repeat 1   (quick run)
//
// For each precision, input order and thread count (--threads, default 1 2) it prints the median seconds of the
// solver's transfers and of a textbook reference run in the same process: a dense uniform
// grid of (mass, momentum) and a plain loop over the particles in input order (one thread).
//   sorted:   particles stored in the solver's bucket order (as after a solver's first sort);
//   shuffled: the same particles stored in random order.
// The solver orders its own particles (sort_into_buckets: block keys, a counting sort of an
// index, grid block allocation, and for scattered storage such as the shuffled input moving
// the particles into bucket order), so its "sort" column is part of its cost and is also
// summed into "sort+P2G" and "step" (sort + P2G + G2P). P2G includes zeroing the grid on both
// sides; the normalisation v_i = (m v)_i / m_i between P2G and G2P is untimed on both sides.
// Double precision runs the library (mpm::particles_to_grid / grid_to_particles); the library
// is double only, so single precision runs the library's scalar-generic loops
// (detail/transfer_loops.h) on a float copy of the particles and float grid channels.
// Before timing, the grids after P2G and the particles after G2P of both implementations are
// compared; the program exits 1 when they differ by more than round-off.
// Last, a short simulation (--steps, default 10): the solver's steps from shuffled input, its
// sorts included, against the same steps from sorted input. The first sort of shuffled input
// moves the particles into bucket order; then they stay nearly ordered, as in a simulation.
// With --adaptive, the same transfers on an adaptive grid (Gao et al. 2017, sec. 6), double
// precision: three levels whose finest has spacing dx, refined in the half x < 1/2 of the
// lattice's box and coarse (4 dx) in the other, particles 2 per axis per cell of their level
// (the lattice spacing on the finest level when dx = 2 spacing), so the coarse half holds 1/64
// of the particles it would hold on the uniform grid and the level jump runs through the
// middle of the body. Reported: the adaptive P2G (ghosts pushed) and G2P (ghosts pulled) per
// particle against the uniform library's per particle on the uniform lattice, same threads;
// the grid's prepare() (its sort) separately. Before timing, the adaptive P2G must conserve
// mass and momentum to round-off, and P2G -> G2P must return an affine velocity field.
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/detail/transfer_loops.h>
#include <mpm/core/memory_budget.h>
#include <mpm/core/transfer.h>

#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <thread>
#include <vector>

using namespace mpm;

namespace {

template <class T>
using V3 = Eigen::Matrix<T, 3, 1>;
template <class T>
using M3 = Eigen::Matrix<T, 3, 3>;

struct Options {
  double spacing = 1.0 / 256;  //!< particle lattice spacing [m]
  double dx = 1.0 / 128;       //!< grid spacing [m]
  int repeat = 3;
  int steps = 10;  //!< steps of the short simulation (0: none)
  std::string precision = "both";
  std::vector<int> threads = {1, 2};  //!< thread counts timed; 1 (the baseline) always first
  bool adaptive = false;              //!< also the adaptive grid's transfers
};

constexpr double dt = 1e-4;  // [s]; G2P advects x by dt v

//! Peak bytes per lattice particle: about 700 measured (912 673 particles, both precisions,
//! 636 MB resident), with room for the adaptive grid's particles.
constexpr double kBytesPerBenchmarkParticle = 1000.0;

// 1. The benchmark particles: a lattice over [1/8, 7/8]^3 with reproducible pseudo-random
//    velocities and affine matrices (a uniform field would hide transfer errors), stored in
//    the solver's bucket order, and a shuffled copy.
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
  SparseGrid<3> grid(Vec<3>::Zero(), Vec<3>::Ones(), o.dx);
  ParticleBuckets<3> buckets;
  P.permute(bucket_order<3, double>(P.x, Kernel{QuadraticBSpline{}}, grid, buckets));
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

// The transfer state of the reference and of the single-precision solver.
template <class T>
struct ParticleArrays {
  std::vector<V3<T>> x, v;
  std::vector<M3<T>> C;
  std::vector<T> mass;

  // A gather in random order when the input is shuffled; the prefetch some way ahead keeps
  // more of its cache misses in flight (5 to 10% faster; docs/performance.md).
  void permute(const std::vector<std::uint32_t>& order) {
    constexpr std::size_t ahead = 32;
    const auto gather = [&](auto& channel) {
      std::remove_reference_t<decltype(channel)> out(order.size());
      for (std::size_t i = 0; i < order.size(); ++i) {
        if (i + ahead < order.size()) detail::prefetch(channel[order[i + ahead]]);
        out[i] = channel[order[i]];
      }
      channel.swap(out);
    };
    gather(x);
    gather(v);
    gather(C);
    gather(mass);
  }

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

// 2. The reference: the textbook APIC transfer (Jiang et al. 2015) on a dense grid, one plain
//    loop over the particles in their input order, quadratic weights computed per particle.
template <class T>
class Reference {
public:
  explicit Reference(const Options& o)
      : n_(static_cast<int>(std::lround(1.0 / o.dx)) + 1),
        dx_(static_cast<T>(o.dx)),
        nodes_(static_cast<std::size_t>(n_) * n_ * n_) {}

  void load(const Particles<3>& input) { P_.assign(input); }

  void p2g() {
    std::fill(nodes_.begin(), nodes_.end(), Node{});
    const T inv_dx = 1 / dx_;
    for (std::size_t p = 0; p < P_.x.size(); ++p) {
      const Weights q(P_.x[p], inv_dx);
      const T m = P_.mass[p];
      const V3<T> mv = m * P_.v[p];
      const M3<T> affine = m * P_.C[p];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) {
            const V3<T> dpos = (V3<T>(i, j, k) - q.fx) * dx_;
            const T weight = q.w[i][0] * q.w[j][1] * q.w[k][2];
            Node& node = at(q.base[0] + i, q.base[1] + j, q.base[2] + k);
            node.mass += weight * m;
            node.momentum += weight * (mv + affine * dpos);
          }
    }
  }

  void normalise() {
    for (Node& g : nodes_) g.momentum = g.mass > 0 ? V3<T>(g.momentum / g.mass) : V3<T>::Zero();
  }

  void g2p() {
    const T inv_dx = 1 / dx_;
    const T inv_D = 4 * inv_dx * inv_dx;  // APIC D_p^-1 for quadratic weights
    for (std::size_t p = 0; p < P_.x.size(); ++p) {
      const Weights q(P_.x[p], inv_dx);
      V3<T> v = V3<T>::Zero();
      M3<T> B = M3<T>::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) {
            const V3<T> dpos = (V3<T>(i, j, k) - q.fx) * dx_;
            const T weight = q.w[i][0] * q.w[j][1] * q.w[k][2];
            const V3<T>& vi = at(q.base[0] + i, q.base[1] + j, q.base[2] + k).momentum;
            v += weight * vi;
            B.noalias() += (weight * vi) * dpos.transpose();
          }
      P_.v[p] = v;
      P_.C[p] = B * inv_D;
      P_.x[p] += static_cast<T>(dt) * v;
    }
  }

  int nodes_per_axis() const { return n_; }
  double mass(const IVec<3>& c) { return at(c[0], c[1], c[2]).mass; }
  Vec<3> momentum(const IVec<3>& c) { return at(c[0], c[1], c[2]).momentum.template cast<double>(); }
  const ParticleArrays<T>& particles() const { return P_; }

private:
  struct Node {
    T mass = 0;
    V3<T> momentum = V3<T>::Zero();  // velocity after normalise()
  };
  // Quadratic B-spline weights of the nodes base, base+1, base+2 on every axis.
  struct Weights {
    Eigen::Vector3i base;
    V3<T> fx;    // particle position minus base [cells]
    V3<T> w[3];  // w[node][axis]
    Weights(const V3<T>& x, T inv_dx) {
      const V3<T> xi = x * inv_dx;
      base = (xi.array() - T(0.5)).floor().template cast<int>();
      fx = xi - base.template cast<T>();
      w[0] = T(0.5) * (T(1.5) - fx.array()).square();
      w[1] = T(0.75) - (fx.array() - T(1)).square();
      w[2] = T(0.5) * (fx.array() - T(0.5)).square();
    }
  };
  Node& at(int i, int j, int k) { return nodes_[(static_cast<std::size_t>(k) * n_ + j) * n_ + i]; }

  int n_;  // nodes per axis; node (i, j, k) at (i, j, k) dx
  T dx_;
  std::vector<Node> nodes_;
  ParticleArrays<T> P_;
};

// 3. The solver: sort_into_buckets, then the bucketed transfers on the sparse grid.
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
template <class Fn>
double timed(Fn&& fn) {
  const auto t0 = Clock::now();
  fn();
  return seconds_since(t0);
}

class DoubleSolver {  // the library
public:
  explicit DoubleSolver(const Options& o) : grid_(Vec<3>::Zero(), Vec<3>::Ones(), o.dx) {}
  void load(const Particles<3>& input) { P_ = input; }
  void sort() { sort_into_buckets(P_, kernel_, grid_, buckets_); }
  void p2g() { particles_to_grid(P_, buckets_, kernel_, scheme_, grid_); }
  void normalise() { momentum_to_velocity(grid_, scheme_); }
  void g2p() { grid_to_particles(P_, buckets_, kernel_, scheme_, grid_, dt); }

  const SparseGrid<3>& grid() const { return grid_; }
  const Particles<3>& particles() const { return P_; }
  double mass(std::size_t k) const { return grid_.mass[k]; }
  Vec<3> momentum(std::size_t k) const { return grid_.velocity[k]; }
  Vec<3> v(std::size_t p) const { return P_.v[p]; }
  Mat<3> C(std::size_t p) const { return P_.C[p]; }

private:
  Kernel kernel_ = QuadraticBSpline{};
  TransferScheme scheme_;  // APIC
  SparseGrid<3> grid_;
  ParticleBuckets<3> buckets_;
  Particles<3> P_;
};

class FloatSolver {  // the library's sort and scalar-generic loops in single precision
public:
  explicit FloatSolver(const Options& o) : grid_(Vec<3>::Zero(), Vec<3>::Ones(), o.dx) {}
  void load(const Particles<3>& input) { P_.assign(input); }
  void sort() {
    sort_into_buckets<3, float>(P_.x, Kernel{kernel_}, grid_, buckets_,
                                [&](const std::vector<std::uint32_t>& order) { P_.permute(order); });
  }
  void p2g() {
    mass_.assign(grid_.node_storage(), 0.0f);
    momentum_.assign(grid_.node_storage(), V3<float>::Zero());
    std::array<detail::BasicChannelView<float>, 4> channels;
    channels[0] = detail::scalar_view(mass_);
    for (int a = 0; a < 3; ++a) channels[a + 1] = detail::component_view<3>(momentum_, a);
    detail::p2g<3, QuadraticBSpline, true>(P_, buckets_, kernel_, grid_, channels);
  }
  void normalise() {
    for (std::size_t k = 0; k < mass_.size(); ++k)
      momentum_[k] = mass_[k] > 0 ? V3<float>(momentum_[k] / mass_[k]) : V3<float>::Zero();
  }
  void g2p() {
    std::array<detail::BasicChannelView<float>, 3> velocity;
    for (int a = 0; a < 3; ++a) velocity[a] = detail::component_view<3>(momentum_, a);
    detail::g2p<3, QuadraticBSpline, false>(P_, buckets_, kernel_, grid_, velocity, 0.0f, static_cast<float>(dt));
  }

  const SparseGrid<3>& grid() const { return grid_; }
  Particles<3> particles() const {
    Particles<3> P;
    for (std::size_t p = 0; p < P_.x.size(); ++p) {
      P.push_back(P_.x[p].cast<double>(), P_.v[p].cast<double>(), P_.mass[p], 0.0, 0);
      P.C.back() = P_.C[p].cast<double>();
    }
    return P;
  }
  double mass(std::size_t k) const { return mass_[k]; }
  Vec<3> momentum(std::size_t k) const { return momentum_[k].cast<double>(); }
  Vec<3> v(std::size_t p) const { return P_.v[p].cast<double>(); }
  Mat<3> C(std::size_t p) const { return P_.C[p].cast<double>(); }

private:
  QuadraticBSpline kernel_;
  SparseGrid<3> grid_;
  ParticleBuckets<3> buckets_;
  ParticleArrays<float> P_;
  std::vector<float> mass_;
  std::vector<V3<float>> momentum_;  // velocity after normalise()
};

// 4. Correctness: both implementations from the same particles. Differences are relative to
//    the largest magnitude of the quantity (pointwise ratios are moot for node momenta near
//    zero); the total mass is compared too, so no mass may land outside the sparse grid.
struct Deviation {
  double mass = 0, momentum = 0, v = 0, C = 0;
  double max() const { return std::max({mass, momentum, v, C}); }
};

template <class Solver, class T>
Deviation compare(const Particles<3>& input, Solver& solver, Reference<T>& ref) {
  solver.load(input);
  solver.sort();  // may store the particles anew in bucket order: the reference gets that order
  solver.p2g();
  ref.load(solver.particles());
  ref.p2g();
  const SparseGrid<3>& grid = solver.grid();
  double err_m = 0, err_p = 0, scale_m = 0, scale_p = 0, total = 0, total_ref = 0;
  for (std::size_t k = 0; k < grid.node_storage(); ++k) {
    const IVec<3> c = grid.node_coord(k);
    if ((c.array() >= ref.nodes_per_axis()).any()) continue;  // block padding past the domain
    err_m = std::max(err_m, std::abs(solver.mass(k) - ref.mass(c)));
    err_p = std::max(err_p, (solver.momentum(k) - ref.momentum(c)).norm());
    scale_m = std::max(scale_m, ref.mass(c));
    scale_p = std::max(scale_p, ref.momentum(c).norm());
    total += solver.mass(k);
    total_ref += ref.mass(c);
  }
  Deviation d;
  const double n = static_cast<double>(input.size());
  d.mass = std::max(err_m / scale_m, std::abs(total - n * input.mass[0]) / (n * input.mass[0]));
  d.momentum = err_p / scale_p;

  solver.normalise();
  solver.g2p();
  ref.normalise();
  ref.g2p();
  double err_v = 0, err_C = 0, scale_v = 0, scale_C = 0;
  for (std::size_t p = 0; p < input.size(); ++p) {
    const Vec<3> v_ref = ref.particles().v[p].template cast<double>();
    const Mat<3> C_ref = ref.particles().C[p].template cast<double>();
    err_v = std::max(err_v, (solver.v(p) - v_ref).norm());
    err_C = std::max(err_C, (solver.C(p) - C_ref).norm());
    scale_v = std::max(scale_v, v_ref.norm());
    scale_C = std::max(scale_C, C_ref.norm());
  }
  d.v = err_v / scale_v;
  d.C = err_C / scale_C;
  return d;
}

// 5. Timing: median over repeats, each from a fresh copy of the input (the copy untimed).
struct Timings {
  double sort = 0, p2g = 0, g2p = 0;
  double step() const { return sort + p2g + g2p; }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

Timings median(const std::vector<Timings>& runs) {
  std::vector<double> s, p, g;
  for (const Timings& t : runs) {
    s.push_back(t.sort);
    p.push_back(t.p2g);
    g.push_back(t.g2p);
  }
  return {median(s), median(p), median(g)};
}

// Fastest run per column: on a shared machine the run least disturbed by other processes.
Timings fastest(const std::vector<Timings>& runs) {
  Timings f = runs.front();
  for (const Timings& t : runs) f = {std::min(f.sort, t.sort), std::min(f.p2g, t.p2g), std::min(f.g2p, t.g2p)};
  return f;
}

template <class Solver>
Timings time_step(Solver& solver) {
  Timings t;
  t.sort = timed([&] { solver.sort(); });
  t.p2g = timed([&] { solver.p2g(); });
  solver.normalise();
  t.g2p = timed([&] { solver.g2p(); });
  return t;
}

template <class Solver>
Timings time_solver(const Particles<3>& input, Solver& solver) {
  solver.load(input);
  return time_step(solver);
}

// A short simulation from the input: the sum of `steps` steps (sort, P2G, G2P), each advecting
// the particles by dt v. From shuffled input the first sort moves the particles into bucket
// order; the later sorts find them nearly ordered and leave them in place.
template <class Solver>
double time_steps(const Particles<3>& input, Solver& solver, int steps) {
  solver.load(input);
  double total = 0;
  for (int s = 0; s < steps; ++s) total += time_step(solver).step();
  return total;
}

template <class T>
Timings time_reference(const Particles<3>& input, Reference<T>& ref) {
  ref.load(input);
  Timings t;
  t.p2g = timed([&] { ref.p2g(); });
  ref.normalise();
  t.g2p = timed([&] { ref.g2p(); });
  return t;
}

struct Row {
  std::string order;
  int threads;
  Timings solver, reference;  // medians
  Timings solver_fastest;
};

const char* verdict(bool met) { return met ? "met" : "MISSED"; }

void report(const char* name, std::size_t n, const Options& o, const std::vector<Row>& rows) {
  std::printf(
      "\n%s precision, %zu particles, dx = %g, median of %d runs [s]; the reference is "
      "single-threaded, x = reference / solver\n",
      name, n, o.dx, o.repeat);
  std::printf("%-8s %3s | %6s %6s %6s %8s %6s | %7s %7s | %5s %5s\n", "order", "thr", "sort", "P2G", "G2P", "sort+P2G",
              "step", "ref P2G", "ref G2P", "P2G x", "G2P x");
  for (const Row& r : rows) {
    const Timings& t = r.solver;
    std::printf("%-8s %3d | %6.3f %6.3f %6.3f %8.3f %6.3f | %7.3f %7.3f | %5.2f %5.2f\n", r.order.c_str(), r.threads,
                t.sort, t.p2g, t.g2p, t.sort + t.p2g, t.step(), r.reference.p2g, r.reference.g2p,
                r.reference.p2g / t.p2g, r.reference.g2p / t.g2p);
  }
  // rows: the sorted input at each of o.threads, then the shuffled input at each.
  const std::size_t counts = o.threads.size();
  const Row& one = rows[0];
  const double p2g_x = one.reference.p2g / one.solver.p2g, g2p_x = one.reference.g2p / one.solver.g2p;
  std::printf("targets (%s):\n", name);
  std::printf("  1 thread, sorted: P2G %.2fx, G2P %.2fx faster than the reference (>= 2): %s\n", p2g_x, g2p_x,
              verdict(p2g_x >= 2 && g2p_x >= 2));
  for (std::size_t i = 0; i < counts; ++i) {
    const Timings &s = rows[i].solver, &h = rows[counts + i].solver;
    const double step = h.step() / s.step(), p2g = (h.sort + h.p2g) / (s.sort + s.p2g);
    std::printf(
        "  %d thread%s, shuffled / sorted: step %.2f, sort+P2G %.2f, sort+P2G / P2G %.2f "
        "(<= 1.3): %s\n",
        rows[i].threads, rows[i].threads > 1 ? "s" : "", step, p2g, (h.sort + h.p2g) / s.p2g,
        verdict(step <= 1.3 && p2g <= 1.3));
  }
  // Scaling against 1 thread, sorted input: speed-ups of the medians and of the fastest runs,
  // and the parallel efficiency (speed-up / threads) of the whole step. The target is stated
  // for 2 threads (>= 1.7); other counts are reported.
  for (std::size_t i = 1; i < counts; ++i) {
    const Timings &s1 = one.solver, &st = rows[i].solver, &f1 = one.solver_fastest, &ft = rows[i].solver_fastest;
    const int t = rows[i].threads;
    const double sp = s1.p2g / st.p2g, sg = s1.g2p / st.g2p, ss = s1.step() / st.step();
    std::printf("  %d threads vs 1, sorted: P2G %.2fx, G2P %.2fx, step %.2fx (efficiency %.2f)%s%s\n", t, sp, sg, ss,
                ss / t, t == 2 ? " (>= 1.7): " : "", t == 2 ? verdict(sp >= 1.7 && sg >= 1.7) : "");
    std::printf(
        "    from the fastest of the %d runs: P2G %.2fx, G2P %.2fx, step %.2fx "
        "(1 thread P2G %.3f s, G2P %.3f s; %d threads %.3f s, %.3f s)\n",
        o.repeat, f1.p2g / ft.p2g, f1.g2p / ft.g2p, f1.step() / ft.step(), f1.p2g, f1.g2p, t, ft.p2g, ft.g2p);
  }
}

// The target's case, shuffled input with the solver's ordering included, over a simulation:
// `steps` steps from shuffled against the same steps from sorted input, pairs of runs
// alternating, the ratio per pair.
template <class Solver>
void report_steps(const Options& o, const char* name, const Particles<3>& sorted_input,
                  const Particles<3>& shuffled_input, Solver& solver) {
  for (int threads : o.threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    std::vector<double> sorted, shuffled, ratio;
    for (int r = 0; r < o.repeat; ++r) {
      sorted.push_back(time_steps(sorted_input, solver, o.steps));
      shuffled.push_back(time_steps(shuffled_input, solver, o.steps));
      ratio.push_back(shuffled.back() / sorted.back());
    }
    const auto [lo, hi] = std::minmax_element(ratio.begin(), ratio.end());
    std::printf(
        "  %d steps (%s), %d thread%s: sorted %.3f s, shuffled %.3f s, shuffled / sorted "
        "%.2f (runs %.2f to %.2f) (<= 1.3): %s\n",
        o.steps, name, threads, threads > 1 ? "s" : "", median(sorted), median(shuffled), median(ratio), *lo, *hi,
        verdict(median(ratio) <= 1.3));
  }
}

template <class Solver, class T>
bool run_precision(const Options& o, const char* name, const Particles<3>& sorted_input) {
  Solver solver(o);
  Reference<T> ref(o);
  const Particles<3> shuffled_input = shuffled(sorted_input);
  const double tolerance = sizeof(T) == 8 ? 1e-10 : 1e-4;
  bool ok = true;
  for (const auto* input : {&sorted_input, &shuffled_input}) {
    const Deviation d = compare(*input, solver, ref);
    std::printf(
        "%s, %s input: max relative difference solver vs reference: node mass %.1e, "
        "momentum %.1e, particle v %.1e, C %.1e (tolerance %.0e) %s\n",
        name, input == &sorted_input ? "sorted" : "shuffled", d.mass, d.momentum, d.v, d.C, tolerance,
        d.max() < tolerance ? "ok" : "FAILED");
    ok = ok && d.max() < tolerance;
  }
  if (!ok) return false;

  // The runs of one order alternate the reference and each thread count, so that load from
  // other processes on a shared machine spreads over all of them alike.
  std::vector<Row> rows;
  for (const auto* input : {&sorted_input, &shuffled_input}) {
    std::vector<Timings> reference;
    std::vector<std::vector<Timings>> solver_runs(o.threads.size());
    for (int r = 0; r < o.repeat; ++r) {
      reference.push_back(time_reference(*input, ref));
      for (std::size_t i = 0; i < o.threads.size(); ++i) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, o.threads[i]);
        solver_runs[i].push_back(time_solver(*input, solver));
      }
    }
    const std::string order = input == &sorted_input ? "sorted" : "shuffled";
    for (std::size_t i = 0; i < o.threads.size(); ++i)
      rows.push_back({order, o.threads[i], median(solver_runs[i]), median(reference), fastest(solver_runs[i])});
  }
  report(name, sorted_input.size(), o, rows);
  if (o.steps > 0) report_steps(o, name, sorted_input, shuffled_input, solver);
  return true;
}

// 6. The adaptive grid: the lattice's particles on the finest level where x < 1/2, a lattice of
//    coarse particles (spacing 4 dx / 2) where x >= 1/2, velocities and C as on the uniform one.
struct AdaptiveInput {
  adaptive::AdaptiveGrid<3> grid;
  Particles<3> P;
  std::vector<std::uint16_t> type;
};

AdaptiveInput adaptive_input(const Options& o) {
  constexpr int levels = 3, coarse = 1 << (levels - 1);
  const int base = static_cast<int>(std::lround(1.0 / (coarse * o.dx)));
  adaptive::CellTree<3> tree(Vec<3>::Zero(), IVec<3>::Constant(base), coarse * o.dx, levels);
  tree.refine_where([](const Vec<3>& lo, const Vec<3>&) { return lo[0] < 0.5 ? levels - 1 : 0; });
  AdaptiveInput in{adaptive::AdaptiveGrid<3>(std::move(tree), 2), {}, {}};
  std::mt19937_64 rng(2017);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const int type : {levels - 1, 0}) {
    const double h = in.grid.particle_size(type), lo = type == 0 ? 0.5 : 0.125, hi = type == 0 ? 0.875 : 0.5;
    const double mass = 1000.0 * h * h * h;
    const int nx = static_cast<int>(std::lround((hi - lo) / h)), n = static_cast<int>(std::lround(0.75 / h));
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < nx; ++i) {
          const Vec<3> x = Vec<3>(lo + (i + 0.5) * h, 0.125 + (j + 0.5) * h, 0.125 + (k + 0.5) * h);
          in.P.push_back(x, Vec<3>(u(rng), u(rng), u(rng)), mass, mass / 1000.0, 0);
          for (int a = 0; a < 9; ++a) in.P.C.back().data()[a] = 10.0 * u(rng);
          in.type.push_back(static_cast<std::uint16_t>(type));
        }
  }
  // Stored in transfer order, as the solver's sort stage leaves them.
  in.grid.prepare(in.P.x, in.type, "prepare", [&](const std::vector<std::uint32_t>& order) {
    in.P.permute(order);
    std::vector<std::uint16_t> t(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) t[i] = in.type[order[i]];
    in.type.swap(t);
  });
  return in;
}

// Total mass and momentum of the particles and of the adaptive grid's real nodes after P2G.
std::pair<double, double> adaptive_conservation(const AdaptiveInput& in) {
  double m_p = 0, m_g = 0;
  Vec<3> p_p = Vec<3>::Zero(), p_g = Vec<3>::Zero();
  for (std::size_t p = 0; p < in.P.size(); ++p) {
    m_p += in.P.mass[p];
    p_p += in.P.mass[p] * in.P.v[p];
  }
  for (int n = 0; n < in.grid.levels(); ++n)
    for (std::size_t k = 0; k < in.grid.level(n).node_storage(); ++k) {
      m_g += in.grid.level(n).mass[k];
      p_g += in.grid.level(n).velocity[k];  // momentum until momentum_to_velocity
    }
  double scale = 0;
  for (std::size_t p = 0; p < in.P.size(); ++p) scale += in.P.mass[p] * in.P.v[p].norm();
  return {std::abs(m_g - m_p) / m_p, (p_g - p_p).norm() / scale};
}

bool run_adaptive(const Options& o, const Particles<3>& uniform_input) {
  AdaptiveInput in = adaptive_input(o);
  const TransferScheme scheme;  // APIC
  adaptive::particles_to_grid(in.P, scheme, in.grid);
  const auto [mass_error, momentum_error] = adaptive_conservation(in);
  // APIC through the ghosts reproduces an affine velocity field (v = A x + b, C = A) through
  // P2G -> G2P: wrong ghost terms (which nodes, which weights) break it, where mass and momentum
  // would still balance.
  double affine_error = 0.0;
  {
    Particles<3> Q = in.P;
    Mat<3> A;
    A << 0.3, -1.2, 0.5, 0.8, 0.1, -0.7, -0.4, 0.9, 0.2;
    const Vec<3> b(0.5, -0.25, 1.0);
    for (std::size_t p = 0; p < Q.size(); ++p) {
      Q.v[p] = A * Q.x[p] + b;
      Q.C[p] = A;
    }
    adaptive::particles_to_grid(Q, scheme, in.grid);
    adaptive::momentum_to_velocity(in.grid, scheme);
    adaptive::pull_velocities(in.grid, scheme);
    adaptive::grid_to_particles(Q, scheme, in.grid, 0.0);
    for (std::size_t p = 0; p < Q.size(); ++p)
      affine_error =
          std::max({affine_error, (Q.v[p] - A * Q.x[p] - b).norm() / b.norm(), (Q.C[p] - A).norm() / A.norm()});
  }
  const bool ok = mass_error < 1e-12 && momentum_error < 1e-12 && affine_error < 1e-10;
  std::size_t irregular = in.grid.irregular().size(), near = 0;
  for (int group = 0; group < in.grid.regular_groups(); ++group) near += in.grid.near_embedded(group).particle.size();
  std::printf(
      "\nadaptive, double precision: %zu particles (%zu on the uniform lattice), 3 levels, finest dx = %g, "
      "refined where x < 1/2; %zu particles near embedded ghosts, %zu irregular; P2G conserves mass to %.1e, "
      "momentum to %.1e (tolerance 1e-12); an affine field comes back to %.1e (tolerance 1e-10) %s\n",
      in.P.size(), uniform_input.size(), o.dx, near, irregular, mass_error, momentum_error, affine_error,
      ok ? "ok" : "FAILED");
  if (!ok) return false;

  DoubleSolver uniform(o);
  std::printf("median of %d runs; ns per particle = s x 1e9 / particles, same thread count\n", o.repeat);
  std::printf("%3s | %9s %9s %9s | %9s %9s | %12s\n", "thr", "prepare", "P2G", "G2P", "unif P2G", "unif G2P",
              "P2G+G2P x");
  const double n_a = static_cast<double>(in.P.size()), n_u = static_cast<double>(uniform_input.size());
  for (const int threads : o.threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    std::vector<double> prepare, p2g, g2p, unif_p2g, unif_g2p;
    for (int r = 0; r < o.repeat; ++r) {
      const Timings u = time_solver(uniform_input, uniform);
      unif_p2g.push_back(u.p2g);
      unif_g2p.push_back(u.g2p);
      Particles<3> P = in.P;  // G2P advects: each run from the same input
      prepare.push_back(timed([&] { in.grid.prepare(P.x, in.type); }));
      p2g.push_back(timed([&] { adaptive::particles_to_grid(P, scheme, in.grid); }));
      adaptive::momentum_to_velocity(in.grid, scheme);
      g2p.push_back(timed([&] {
        adaptive::pull_velocities(in.grid, scheme);
        adaptive::grid_to_particles(P, scheme, in.grid, dt);
      }));
    }
    const auto ns = [](double s, double n) { return s * 1e9 / n; };
    const double a = ns(median(p2g) + median(g2p), n_a), b = ns(median(unif_p2g) + median(unif_g2p), n_u);
    std::printf("%3d | %9.1f %9.1f %9.1f | %9.1f %9.1f | %12.2f%s\n", threads, ns(median(prepare), n_a),
                ns(median(p2g), n_a), ns(median(g2p), n_a), ns(median(unif_p2g), n_u), ns(median(unif_g2p), n_u), a / b,
                a / b <= 1.5 ? " (<= 1.5: met)" : " (<= 1.5: MISSED)");
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  CLI::App app{"Particle <-> grid transfer benchmark (Gao et al. 2017, Table 1)"};
  app.add_option("--particles-spacing", o.spacing, "particle lattice spacing [m] (default 1/256)")
      ->check(CLI::Range(1e-3, 0.25));
  app.add_option("--dx", o.dx, "grid spacing [m] (default 1/128)")->check(CLI::Range(1.0 / 512, 1.0 / 16));
  app.add_option("--repeat", o.repeat, "timed runs per configuration; the median is reported")
      ->check(CLI::Range(1, 100));
  app.add_option("--steps", o.steps, "steps of the simulation from sorted and from shuffled input (0: none)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--precision", o.precision, "float, double or both")
      ->check(CLI::IsMember({"float", "double", "both"}));
  app.add_option("--threads", o.threads,
                 "thread counts to time, e.g. --threads 1 2 4 16 (default 1 2); 1 is added first when missing")
      ->check(CLI::Range(1, cores, "thread count in [1, cores of this machine = " + std::to_string(cores) + "]"));
  app.add_flag("--adaptive", o.adaptive, "also the transfers on a 3-level adaptive grid (double precision)");
  CLI11_PARSE(app, argc, argv);
  o.threads.erase(std::remove(o.threads.begin(), o.threads.end(), 1), o.threads.end());
  o.threads.insert(o.threads.begin(), 1);  // the baseline of every ratio

  const double per_axis = std::round(0.75 / o.spacing) + 1.0;
  if (const std::string why = memory_shortfall(per_axis * per_axis * per_axis * kBytesPerBenchmarkParticle);
      !why.empty()) {
    std::fprintf(stderr,
                 "bench_transfer: --particles-spacing %g: %.0f particles need %s; choose a larger spacing "
                 "(accepted range [1e-3, 0.25] m, memory permitting)\n",
                 o.spacing, per_axis * per_axis * per_axis, why.c_str());
    return 2;
  }
  const Particles<3> input = lattice(o);
  bool ok = true;
  if (o.precision != "float") ok = run_precision<DoubleSolver, double>(o, "double", input) && ok;
  if (o.precision != "double") ok = run_precision<FloatSolver, float>(o, "float", input) && ok;
  if (o.adaptive) ok = run_adaptive(o, input) && ok;
  return ok ? 0 : 1;
}
