// bench_step: the whole step of the library against a reference step in the same process, in
// ns per particle-step per core, at the thread counts given.
//
//   bench_step                                   (sand and jello, 64 cells, 1 and 2 threads)
//   bench_step --case sand --cells 80 --steps 20 --threads 1 2 4 8 16
//   bench_step --case fluid coupled              (builds with libcoupling: bench_step_coupled.cpp)
//
// Solid cases (3D, domain [0, 1]^3 with sticky walls, dx = 1 / cells, 8 particles per cell):
//   sand:  a column 0.4 x 0.5 x 0.4 m of Drucker-Prager sand (Hencky StVK, 32 deg) collapsing
//          under gravity from rest on the floor: every stage of the granular step, the
//          return map included;
//   jello: a fixed-corotated cube 0.4 m wide thrown onto the floor at (1, -2, 0.5) m/s from
//          touching it (the sticky floor strains it from the first step).
// The library runs the scene's own pipeline (solid::load_solid_scene: time step, sort, P2G,
// stress forces, grid update, walls, G2P with the deformation update, return map). The reference is the
// straightforward version of that step, one thread, kept here: a dense grid, one loop over the
// particles that computes each stress (Eigen's JacobiSVD) and scatters mass, APIC momentum and
// force, a loop over the nodes, and one loop that gathers v, C and grad v, updates F and
// projects it (Klar et al. 2016 with the volume correction of Tampubolon et al. 2017). It takes
// the library's time steps, so the two integrate the same equations: before timing, the
// totals of momentum, mass-weighted position, kinetic energy, F and the plastic state after
// --steps steps are compared, and the program exits 1 when they differ beyond round-off.
//
// Timing: each thread count runs --steps steps from the seeded scene, --repeat times,
// alternating with the reference; the median is reported. ns per particle-step per core is
// seconds x threads x 1e9 / (particles x steps): equal across thread counts when the step
// scales perfectly.
#include <mpm/core/memory_budget.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>

#include "step_timing.h"

#include <tbb/global_control.h>
#include <CLI/CLI.hpp>
#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

using namespace mpm;

namespace {

struct Options {
  std::vector<std::string> cases = {"sand", "jello"};
  int cells = 64;  //!< grid cells per metre (the domain is the unit cube)
  int steps = 10;
  int repeat = 3;
  std::vector<int> threads = {1, 2};
  int setup_reuse = 20;  //!< fluid, coupled: pressure.setup_reuse of the library's scene
};

// 1. The scenes, as scene files would state them.
struct Case {
  std::string yaml;
  double mu = 0, lambda = 0;  // Lame parameters [Pa]
  bool sand = false;
  double friction_angle = 32;  // [deg], sand only
};

Case make_case(const std::string& name, int cells) {
  const double dx = 1.0 / cells, E = name == "sand" ? 3e6 : 1e5, nu = 0.3;
  const std::string floor = bench::yaml_number(2 * dx);  // the inner face of the floor's wall layer
  Case c;
  c.sand = name == "sand";
  c.mu = E / (2 * (1 + nu));
  c.lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  c.yaml = "dim: 3\ndomain: {lo: [0, 0, 0], hi: [1, 1, 1]}\ngrid: {dx: " + bench::yaml_number(dx) +
           "}\nwalls: {contact: sticky}\ntime: {end: 1, frame_dt: 1, cfl: 0.4}\ngravity: [0, -9.81, 0]\n";
  if (c.sand)
    c.yaml +=
        "materials: [{name: sand, density: 2650, youngs_modulus: 3.0e6, poisson_ratio: 0.3, elasticity: hencky_stvk,"
        " plasticity: {model: drucker_prager, friction_angle: 32}}]\n"
        "bodies: [{shape: box, material: sand, lo: [0.3, " +
        floor + ", 0.3], hi: [0.7, " + bench::yaml_number(2 * dx + 0.5) + ", 0.7]}]\n";
  else
    c.yaml +=
        "materials: [{name: jello, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, "
        "elasticity: fixed_corotated}]\n"
        "bodies: [{shape: box, material: jello, lo: [0.3, " +
        floor + ", 0.3], hi: [0.7, " + bench::yaml_number(2 * dx + 0.4) + ", 0.7], velocity: [1, -2, 0.5]}]\n";
  return c;
}

solid::SolidScene<3> load(const Case& c) { return solid::load_solid_scene<3>(Config::parse(c.yaml, "bench_step")); }

// 2. The reference step.
class Reference {
public:
  Reference(const Case& c, int cells) : c_(c), n_(cells + 1), dx_(1.0 / cells), nodes_(std::size_t(n_) * n_ * n_) {
    const double a = std::sin(c.friction_angle * std::numbers::pi / 180);
    alpha_ = std::sqrt(2.0 / 3.0) * 2 * a / (3 - a);  // cohesion 0: k = 0
  }

  void load(const Particles<3>& P) {
    x_ = P.x;
    v_ = P.v;
    C_ = P.C;
    mass_ = P.mass;
    volume0_ = P.volume0;
    F_ = solid::elastic_F(P);
    plastic_ = solid::plastic_state(P);
  }

  void step(double dt) {
    std::fill(nodes_.begin(), nodes_.end(), Node{});
    const double D_inv = 4 / (dx_ * dx_);  // APIC, quadratic weights
    for (std::size_t p = 0; p < x_.size(); ++p) {
      const Weights q(x_[p], dx_);
      const Mat<3> stress = volume0_[p] * kirchhoff(F_[p]);
      const Mat<3> affine = mass_[p] * C_[p];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) {
            Node& node = at(q.base + Eigen::Vector3i(i, j, k));
            const double w = q.w[i][0] * q.w[j][1] * q.w[k][2];
            node.mass += w * mass_[p];
            node.momentum += w * (mass_[p] * v_[p] + affine * ((Vec<3>(i, j, k) - q.fx) * dx_));
            node.force -= stress * q.gradient(i, j, k);
          }
    }
    const double wall = 2 * dx_ * (1 + 1e-9);  // sticky walls: nodes within 2 dx of a face
    for (int k = 0; k < n_; ++k)
      for (int j = 0; j < n_; ++j)
        for (int i = 0; i < n_; ++i) {
          Node& node = at({i, j, k});
          if (node.mass <= 0) continue;
          node.momentum = node.momentum / node.mass + dt * (node.force / node.mass + Vec<3>(0, -9.81, 0));
          const Vec<3> x = Vec<3>(i, j, k) * dx_;
          if ((x.array() <= wall).any() || ((1 - x.array()) <= wall).any()) node.momentum.setZero();
        }
    for (std::size_t p = 0; p < x_.size(); ++p) {
      const Weights q(x_[p], dx_);
      Vec<3> v = Vec<3>::Zero();
      Mat<3> B = Mat<3>::Zero(), grad_v = Mat<3>::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) {
            const Vec<3>& vi = at(q.base + Eigen::Vector3i(i, j, k)).momentum;
            const double w = q.w[i][0] * q.w[j][1] * q.w[k][2];
            v += w * vi;
            B += w * vi * ((Vec<3>(i, j, k) - q.fx) * dx_).transpose();
            grad_v += vi * q.gradient(i, j, k).transpose();
          }
      F_[p] = (Mat<3>::Identity() + dt * grad_v) * F_[p];
      if (c_.sand) project(F_[p], plastic_[p]);
      v_[p] = v;
      C_[p] = B * D_inv;
      x_[p] += dt * v;
    }
  }

  // The totals the library's run is compared on.
  std::vector<double> totals() const { return make_totals(x_, v_, mass_, F_, plastic_); }

  static std::vector<double> make_totals(const std::vector<Vec<3>>& x, const std::vector<Vec<3>>& v,
                                         const std::vector<double>& mass, const std::vector<Mat<3>>& F,
                                         const std::vector<double>& plastic) {
    std::vector<double> t(12, 0.0);  // momentum (3), m x (3), kinetic energy, sum F (4: trace, off), plastic
    for (std::size_t p = 0; p < x.size(); ++p) {
      for (int a = 0; a < 3; ++a) t[a] += mass[p] * v[p][a];
      for (int a = 0; a < 3; ++a) t[3 + a] += mass[p] * x[p][a];
      t[6] += 0.5 * mass[p] * v[p].squaredNorm();
      t[7] += F[p].trace();
      t[8] += F[p](0, 1) + F[p](1, 0);
      t[9] += F[p](1, 2) + F[p](2, 1);
      t[10] += (F[p] - Mat<3>::Identity()).squaredNorm();
      t[11] += plastic[p];
    }
    return t;
  }

private:
  struct Node {
    double mass = 0;
    Vec<3> momentum = Vec<3>::Zero();  // velocity after the grid update
    Vec<3> force = Vec<3>::Zero();
  };
  struct Weights {  // quadratic B-spline weights of the nodes base .. base + 2 on each axis
    Eigen::Vector3i base;
    Vec<3> fx;
    Vec<3> w[3], dw[3];
    Weights(const Vec<3>& x, double h) {
      const Vec<3> xi = x / h;
      base = (xi.array() - 0.5).floor().cast<int>();
      fx = xi - base.cast<double>();
      w[0] = 0.5 * (1.5 - fx.array()).square();
      w[1] = 0.75 - (fx.array() - 1).square();
      w[2] = 0.5 * (fx.array() - 0.5).square();
      dw[0] = (fx.array() - 1.5) / h;
      dw[1] = -2 * (fx.array() - 1) / h;
      dw[2] = (fx.array() - 0.5) / h;
    }
    Vec<3> gradient(int i, int j, int k) const {
      return {dw[i][0] * w[j][1] * w[k][2], w[i][0] * dw[j][1] * w[k][2], w[i][0] * w[j][1] * dw[k][2]};
    }
  };

  // Kirchhoff stress tau = P F^T.
  Mat<3> kirchhoff(const Mat<3>& F) const {
    const Eigen::JacobiSVD<Mat<3>> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Mat<3>& U = svd.matrixU();
    if (c_.sand) {  // Hencky StVK: tau = U diag(2 mu eps + lambda tr eps) U^T, eps = log sigma
      const Vec<3> eps = svd.singularValues().array().log();
      const Vec<3> tau = 2 * c_.mu * eps + Vec<3>::Constant(c_.lambda * eps.sum());
      return U * tau.asDiagonal() * U.transpose();
    }
    // fixed corotated: tau = 2 mu (F - R) F^T + lambda (J - 1) J I, R = U V^T a rotation
    Mat<3> Ur = U;
    if ((U * svd.matrixV().transpose()).determinant() < 0) Ur.col(2) *= -1;
    const Mat<3> R = Ur * svd.matrixV().transpose();
    const double J = F.determinant();
    return 2 * c_.mu * (F - R) * F.transpose() + c_.lambda * (J - 1) * J * Mat<3>::Identity();
  }

  // Drucker-Prager return map on eps = log sigma + plastic / 3 (cohesion 0).
  void project(Mat<3>& F, double& plastic) const {
    const Eigen::JacobiSVD<Mat<3>> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Vec<3> eps = svd.singularValues().array().log() + plastic / 3;
    const double trace = eps.sum();
    Vec<3> H = eps;
    if (trace >= 0) {  // beyond the apex: no stress, store the expansion
      H.setZero();
      plastic = trace;
    } else {
      const Vec<3> tau = 2 * c_.mu * eps + Vec<3>::Constant(c_.lambda * trace);
      const double y = (tau - Vec<3>::Constant(tau.sum() / 3)).norm() + alpha_ * tau.sum();
      if (y <= 0 && plastic == 0) return;
      if (y > 0) {
        const Vec<3> dev = eps - Vec<3>::Constant(trace / 3);
        H -= y / (2 * c_.mu * dev.norm()) * dev;
      }
      plastic = 0;
    }
    F = svd.matrixU() * H.array().exp().matrix().asDiagonal() * svd.matrixV().transpose();
  }

  Node& at(const Eigen::Vector3i& c) { return nodes_[(std::size_t(c[2]) * n_ + c[1]) * n_ + c[0]]; }

  Case c_;
  int n_;
  double dx_, alpha_ = 0;
  std::vector<Node> nodes_;
  std::vector<Vec<3>> x_, v_;
  std::vector<Mat<3>> C_, F_;
  std::vector<double> mass_, volume0_, plastic_;
};

// 3. Timing (step_timing.h).
using bench::Clock;
using bench::seconds_since;

struct LibraryRun {
  double seconds = 0;
  std::vector<double> dt;
  std::vector<double> totals;
  StageTimes stages;
  std::size_t particles = 0;
};

LibraryRun run_library(const Case& c, int steps) {
  solid::SolidScene<3> scene = load(c);
  Pipeline<MpmState<3>> pipeline = solid::make_solid_pipeline(scene);
  LibraryRun run;
  run.particles = scene.state.particles.size();
  const auto t0 = Clock::now();
  for (int s = 0; s < steps; ++s) {
    pipeline.step(scene.state);
    run.dt.push_back(scene.state.dt);
  }
  run.seconds = seconds_since(t0);
  const Particles<3>& P = scene.state.particles;
  run.totals = Reference::make_totals(P.x, P.v, P.mass, solid::elastic_F(P), solid::plastic_state(P));
  run.stages = pipeline.times();
  return run;
}

double run_reference(const Case& c, int cells, const std::vector<double>& dt, std::vector<double>* totals) {
  const solid::SolidScene<3> scene = load(c);  // the seeded particles, in seeding order
  Reference ref(c, cells);
  ref.load(scene.state.particles);
  const auto t0 = Clock::now();
  for (double h : dt) ref.step(h);
  const double seconds = seconds_since(t0);
  if (totals) *totals = ref.totals();
  return seconds;
}

bool run_case(const Options& o, const std::string& name) {
  const Case c = make_case(name, o.cells);
  const double reference_bytes = std::pow(o.cells + 1.0, 3) * 56.0;  // the dense grid
  const std::string shortfall = memory_shortfall(reference_bytes);
  if (!shortfall.empty()) {
    std::fprintf(stderr, "bench_step: --cells %d: the reference's dense grid needs %s\n", o.cells, shortfall.c_str());
    return false;
  }

  // Correctness: the library's steps and the reference on the same time steps.
  LibraryRun check;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, o.threads.back());
    check = run_library(c, o.steps);
  }
  std::vector<double> ref_totals;
  run_reference(c, o.cells, check.dt, &ref_totals);
  // Momentum, m x, kinetic energy, F (trace, off-diagonal pairs), |F - I|^2, plastic state.
  const double d =
      bench::max_group_difference(check.totals, ref_totals, {{0, 3}, {3, 6}, {6, 7}, {7, 10}, {10, 11}, {11, 12}});
  const double tolerance = 1e-9;
  std::printf(
      "\n%s: %zu particles, dx = 1/%d, %d steps (dt %.3g .. %.3g s); library vs reference totals: max "
      "relative difference %.1e (tolerance %.0e) %s\n",
      name.c_str(), check.particles, o.cells, o.steps, *std::min_element(check.dt.begin(), check.dt.end()),
      *std::max_element(check.dt.begin(), check.dt.end()), d, tolerance, d < tolerance ? "ok" : "FAILED");
  if (!(d < tolerance)) {
    const char* names[] = {"p_x", "p_y",  "p_z",       "mx_x",      "mx_y",      "mx_z",
                           "KE",  "tr F", "F_xy+F_yx", "F_yz+F_zy", "|F - I|^2", "plastic"};
    for (std::size_t i = 0; i < ref_totals.size(); ++i)
      std::printf("  %-10s library %.15g reference %.15g\n", names[i], check.totals[i], ref_totals[i]);
    return false;
  }

  bench::time_and_report(
      o.threads, o.repeat, static_cast<double>(check.particles) * o.steps,
      [&] { return run_reference(c, o.cells, check.dt, nullptr); },
      [&] {
        const LibraryRun run = run_library(c, o.steps);
        return bench::StepRun{run.seconds, run.stages};
      });
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  CLI::App app{"The whole step: library against a reference in the same process, ns per particle-step per core"};
#ifdef SEDIMENT_BENCH_COUPLED
  const std::vector<std::string> names = {"sand", "jello", "fluid", "coupled"};
#else
  const std::vector<std::string> names = {"sand", "jello"};  // fluid, coupled: built with libcoupling only
#endif
  app.add_option("--case", o.cases, "sand, jello, fluid, coupled (default sand jello)")->check(CLI::IsMember(names));
  app.add_option("--cells", o.cells, "grid cells per axis of the unit cube (default 64)")->check(CLI::Range(16, 512));
  app.add_option("--steps", o.steps, "steps per run (default 10)")->check(CLI::Range(1, 10000));
  app.add_option("--repeat", o.repeat, "runs per configuration; the median is reported")->check(CLI::Range(1, 100));
  app.add_option("--threads", o.threads, "thread counts to time (default 1 2); 1 is added first when missing")
      ->check(CLI::Range(1, cores, "thread count in [1, cores of this machine = " + std::to_string(cores) + "]"));
  app.add_option("--setup-reuse", o.setup_reuse,
                 "fluid, coupled: the library's pressure.setup_reuse (default 20, the scenes' default)")
      ->check(CLI::Range(1, 1000));
  CLI11_PARSE(app, argc, argv);
  o.threads.erase(std::remove(o.threads.begin(), o.threads.end(), 1), o.threads.end());
  o.threads.insert(o.threads.begin(), 1);  // the baseline of every speed-up

  bool ok = true;
  try {
    for (const std::string& name : o.cases)
      ok = (name == "sand" || name == "jello"
                ? run_case(o, name)
                : bench::run_coupled_case(name, o.cells, o.steps, o.repeat, o.threads, o.setup_reuse)) &&
           ok;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_step: %s\n", e.what());
    return 2;
  }
  return ok ? 0 : 1;
}
