// Axis-aligned manufactured solution (Wallstedt and Guilkey 2008, "An evaluation of explicit
// time integration schemes for use with the generalized interpolation material point method",
// J. Comput. Phys. 227, 9628-9642): observed convergence of the explicit MPM solid stages under
// finite deformation. docs/verification.md has the measured tables.
//
// Field. In the unit square 0 <= X, Y <= 1, with k = 2 pi and c = sqrt(E / rho0),
//   u_x = A sin(k X) sin(c pi t),   u_y = A sin(k Y) sin(c pi t + pi) = -A sin(k Y) sin(c pi t),
// E = 1e7 Pa, nu = 0.3, rho0 = 1000 kg/m^3 (c = 100 m/s), A = 0.05 m in the paper.
// F = I + Grad u is diagonal, F_xx = 1 + A k cos(k X) sin(c pi t), F_yy likewise in Y,
// J = F_xx F_yy; u vanishes on the edges of the square and is 1-periodic in X and Y.
//
// Body force. Compressible neo-Hookean (constitutive::NeoHookean, as in the paper):
//   P = mu (F - F^-T) + lambda ln J F^-T,   diagonal here, P_xx = mu F_xx + (lambda ln J - mu) / F_xx.
// Balance of momentum in the reference configuration, rho0 u_tt = Div P + rho0 b, gives
// b = u_tt - Div P / rho0. P_xx depends on X only through F_xx (J's Y factor is constant in X):
//   dP_xx/dF_xx = mu + (mu + lambda (1 - ln J)) / F_xx^2,   dF_xx/dX = -k^2 u_x,   u_tt,x = -(c pi)^2 u_x,
// so, per unit mass [m/s^2],
//   b_x = u_x [ -(c pi)^2 + (k^2 / rho0) (mu + (mu + lambda (1 - ln J)) / F_xx^2) ],
// and b_y the same with (u_y, F_yy). Written with K = ln J - 1 this is
// pi^2 u_x (4 mu / rho0 - c^2 - 4 (lambda K - mu) / (rho0 F_xx^2)), the form of the paper
// (and of Uintah's MMS::computeExternalForceForMMS, which uses k = pi).
// The force acts on each particle at its reference position, f_i^ext = sum_p m_p b(X_p, t^n) w_ip,
// added to the grid force before the explicit update like gravity: the same quadrature as the
// momentum, so the weak form stays consistent. X_p is kept in a side array aligned with the
// particle storage, which the sort leaves in place.
//
// Boundary. The test runs the periodic problem: before every sort each particle of the square
// gets images shifted by (+-1, 0), (0, +-1), (+-1, +-1) within a band 5 dx wide, copies of its
// whole state, so every node that a particle of the square reaches has its full periodic
// stencil. A Dirichlet wall would not do for B-splines: the basis function of the first interior
// node does not vanish on the wall, so the weak form keeps a boundary term sigma(0) N_i(0) that
// the wall velocity cannot cancel, a first-order boundary error (test_vibrating_bar.cpp measures
// it) that would hide the interior order.
//
// Initial state: x_p = X_p at sub-cell centres (2 x 2 per cell), F = I, v = v(X, 0),
// APIC C = Grad v(X, 0). u(X, 0) = 0 and b(X, 0) = 0, so the exact acceleration vanishes at
// t = 0 and symplectic Euler (leapfrog) is second order in time from the first step;
// dt = T / ceil(T c_p / (0.5 dx)) with the P-wave speed c_p. Errors e_p = x_p - X_p - u(X_p, t)
// relative to A over the particles of the square, at T = 2 / c (one period of the time factor):
// max_p |e_p(T)|, rms_p |e_p(T)|, and max over all steps and particles.
#include "convergence.h"

#include <mpm/adaptive/particle_levels.h>
#include <mpm/adaptive/refinement.h>
#include <mpm/core/advance.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/stages/ghost_velocities.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/core/stages/time_step_control.h>
#include <mpm/geometry/seeding.h>
#include <mpm/solid/material.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/stress_forces.h>

#include <mpm/constitutive/neo_hookean.h>

#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <variant>
#include <vector>

using namespace mpm;
using verification::Level;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kWaveNumber = 2.0 * kPi;  // k [1/m]

//! The manufactured field and its body force (header comment).
struct AxisAligned {
  double amplitude;   // A [m]
  double density;     // rho0 [kg/m^3]
  double mu, lambda;  // [Pa]
  double c;           // sqrt(E / rho0) [m/s]

  double time_factor(double t) const { return std::sin(c * kPi * t); }
  // Sign of axis a's time factor: u_y carries sin(c pi t + pi) = -sin(c pi t).
  static double sign(int a) { return a == 0 ? 1.0 : -1.0; }

  Vec<2> displacement(const Vec<2>& X, double t) const {
    Vec<2> u;
    for (int a = 0; a < 2; ++a) u[a] = sign(a) * amplitude * std::sin(kWaveNumber * X[a]) * time_factor(t);
    return u;
  }
  Vec<2> velocity(const Vec<2>& X, double t) const {
    Vec<2> v;
    for (int a = 0; a < 2; ++a)
      v[a] = sign(a) * amplitude * c * kPi * std::sin(kWaveNumber * X[a]) * std::cos(c * kPi * t);
    return v;
  }
  //! Grad_X v, which at t = 0 (F = I) is also the spatial velocity gradient.
  Mat<2> velocity_gradient(const Vec<2>& X, double t) const {
    Mat<2> L = Mat<2>::Zero();
    for (int a = 0; a < 2; ++a)
      L(a, a) = sign(a) * amplitude * c * kPi * kWaveNumber * std::cos(kWaveNumber * X[a]) * std::cos(c * kPi * t);
    return L;
  }
  Vec<2> body_force(const Vec<2>& X, double t) const {
    const Vec<2> u = displacement(X, t);
    Vec<2> F;
    for (int a = 0; a < 2; ++a)
      F[a] = 1.0 + sign(a) * amplitude * kWaveNumber * std::cos(kWaveNumber * X[a]) * time_factor(t);
    const double log_J = std::log(F[0] * F[1]);
    Vec<2> b;
    for (int a = 0; a < 2; ++a)
      b[a] = u[a] * (-(c * kPi) * (c * kPi) +
                     kWaveNumber * kWaveNumber / density * (mu + (mu + lambda * (1.0 - log_J)) / (F[a] * F[a])));
    return b;
  }
};

bool in_square(const Vec<2>& X) { return X[0] > 0.0 && X[0] < 1.0 && X[1] > 0.0 && X[1] < 1.0; }

//! Reference positions X_p: a particle channel, so that they follow the particles when the
//! sort stores them anew (adaptive_grid.h).
std::vector<Vec<2>>& reference_positions(Particles<2>& P) {
  return P.add_channel<Vec<2>>("reference_x", Vec<2>::Zero(), ChannelUse{});
}
const std::vector<Vec<2>>& reference_positions(const Particles<2>& P) { return P.channel<Vec<2>>("reference_x"); }

//! Replaces the periodic images of the previous step by fresh copies of the particles of the
//! unit square, within `band` [m] of it.
class PeriodicImages final : public Stage<MpmState<2>> {
public:
  explicit PeriodicImages(double band) : band_(band) {}
  std::string name() const override { return "periodic_images"; }
  std::vector<std::string> reads() const override { return channels(); }
  std::vector<std::string> writes() const override { return channels(); }
  void run(MpmState<2>& s) override {
    Particles<2> next;
    solid::add_solid_channels(next);
    // On an adaptive grid every image keeps its particle's type: the refinement is periodic.
    if (s.adaptive) adaptive::add_level_channel(next, s.adaptive->tree());
    std::vector<Mat<2>>& next_F = solid::elastic_F(next);
    std::vector<Vec<2>>& X = reference_positions(next);
    auto append = [&](const Particles<2>& from, const std::vector<Mat<2>>& F_from, const std::vector<Vec<2>>& X_from,
                      std::size_t p, const Vec<2>& shift) {
      next.push_back(from.x[p] + shift, from.v[p], from.mass[p], from.volume0[p], from.material[p]);
      next.C.back() = from.C[p];
      next_F.back() = F_from[p];
      if (s.adaptive)
        next.channel<std::uint16_t>(adaptive::kParticleLevel).back() =
            from.channel<std::uint16_t>(adaptive::kParticleLevel)[p];
      X.back() = X_from[p] + shift;
    };
    const std::vector<Mat<2>>& F_now = solid::elastic_F(s.particles);
    const std::vector<Vec<2>>& X_now = reference_positions(std::as_const(s.particles));
    for (std::size_t p = 0; p < s.particles.size(); ++p)
      if (in_square(X_now[p])) append(s.particles, F_now, X_now, p, Vec<2>::Zero());
    // A snapshot of the square, since `next` grows while its images are appended.
    const Particles<2> square = next;
    const std::vector<Mat<2>>& F_square = solid::elastic_F(square);
    const std::vector<Vec<2>>& X_square = reference_positions(square);
    for (int sy = -1; sy <= 1; ++sy)
      for (int sx = -1; sx <= 1; ++sx) {
        if (sx == 0 && sy == 0) continue;
        const Vec<2> shift(sx, sy);
        for (std::size_t p = 0; p < square.size(); ++p) {
          const Vec<2> y = square.x[p] + shift;
          if (y.minCoeff() > -band_ && y.maxCoeff() < 1.0 + band_) append(square, F_square, X_square, p, shift);
        }
      }
    s.particles = std::move(next);
  }

private:
  static std::vector<std::string> channels() {
    return {"particle.x",       "particle.v",        "particle.C", "particle.mass",
            "particle.volume0", "particle.material", "particle.F", "particle.reference_x"};
  }
  double band_;
};

//! f_i += sum_p m_p b(X_p, t^n) w_ip on the grid force.
class ManufacturedBodyForce final : public Stage<MpmState<2>> {
public:
  explicit ManufacturedBodyForce(const AxisAligned& field) : field_(field) {}
  std::string name() const override { return "body_force"; }
  std::vector<std::string> reads() const override {
    return {"grid.force", "particle.x", "particle.mass", "particle.reference_x"};
  }
  std::vector<std::string> writes() const override { return {"grid.force"}; }
  void run(MpmState<2>& s) override {
    const Particles<2>& P = s.particles;
    const std::vector<Vec<2>>& X = reference_positions(P);
    if (s.adaptive) {  // on each particle's transfer level, ghosts pushed to their real nodes
      adaptive::AdaptiveGrid<2>& grid = *s.adaptive;
      std::vector<std::vector<Vec<2>>*> force;
      for (int n = 0; n < grid.levels(); ++n) force.push_back(&grid.level(n).force);
      for (std::size_t p = 0; p < P.size(); ++p) {
        const Vec<2> f = P.mass[p] * field_.body_force(X[p], s.time);
        const int n = grid.transfer_level(p);
        grid.for_each_weight(n, grid.half_cells(p), P.x[p], [&](Index k, double w, const Vec<2>&, const Vec<2>&) {
          (*force[static_cast<std::size_t>(n)])[static_cast<std::size_t>(k)] += w * f;
        });
      }
      grid.push(force);
      return;
    }
    const CellMap<2> map(s.grid);
    std::visit(
        [&](const auto& kernel) {
          constexpr int S = std::decay_t<decltype(kernel)>::support;
          for (std::size_t p = 0; p < P.size(); ++p) {
            const Vec<2> f = P.mass[p] * field_.body_force(X[p], s.time);
            const Vec<2> xi = map(P.x[p]);
            int base[2];
            double w[2][S], dw[2][S];
            for (int a = 0; a < 2; ++a) kernel(xi[a], base[a], w[a], dw[a]);
            for (int j = 0; j < S; ++j)
              for (int i = 0; i < S; ++i) {
                const Index k = s.grid.node_index(IVec<2>(base[0] + i, base[1] + j));
                s.grid.force[static_cast<std::size_t>(k)] += w[0][i] * w[1][j] * f;
              }
          }
        },
        s.kernel);
  }

private:
  const AxisAligned& field_;
};

struct MmsSettings {
  double amplitude = 0.05;  // A [m], the paper's value
  double end_time = 0.02;   // T [s]: one period 2 / c of the time factor
  double youngs = 1e7;      // E [Pa]
  double poisson = 0.3;
  double density = 1000.0;  // rho0 [kg/m^3]
  double wave_cfl = 0.5;
};

//! Displacement errors relative to A over the particles of the square.
struct MmsErrors {
  Level final_max;       // max_p |e_p(T)|
  Level final_rms;       // rms_p |e_p(T)|
  Level space_time_max;  // max_n max_p |e_p(t^n)|
  Level stripe_max;      // max_n max_p |e_p(t^n)| over the particles of the stripe 0.25 < X < 0.75
};

//! The stripe that the adaptive runs refine, 0.25 < X < 0.75, and its periodic images.
bool in_stripe(const Vec<2>& X) {
  const double f = X[0] - std::floor(X[0]);
  return f > 0.25 && f < 0.75;
}

double max_error(const MpmState<2>& state, const AxisAligned& field, double* rms = nullptr,
                 double* stripe_max = nullptr) {
  double e_max = 0.0, e_sq = 0.0, e_stripe = 0.0;
  std::size_t count = 0;
  const Particles<2>& P = state.particles;
  const std::vector<Vec<2>>& X = reference_positions(P);
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (!in_square(X[p])) continue;
    const double e = (P.x[p] - X[p] - field.displacement(X[p], state.time)).norm() / field.amplitude;
    e_max = std::max(e_max, e);
    if (in_stripe(X[p])) e_stripe = std::max(e_stripe, e);
    e_sq += e * e;
    ++count;
  }
  if (rms) *rms = std::sqrt(e_sq / static_cast<double>(count));
  if (stripe_max) *stripe_max = std::max(*stripe_max, e_stripe);
  return e_max;
}

// levels > 1: an adaptive grid (mpm/adaptive/) whose finest spacing is 1 / cells, refined to the
// finest level in the stripe 0.25 < X < 0.75 and its periodic images (so every image lies in a
// leaf of its particle's type) and `levels` - 1 times coarser elsewhere. The particles are
// seeded on the finest lattice and regrouped to the leaves' levels (the kernel argument is
// then unused: each particle transfers with GIMP weights of its own box, half a cell of its
// level, the same scheme as uGIMP with h = 1/4 on a uniform grid).
MmsErrors run_mms(int cells, const Kernel& kernel, const MmsSettings& in, int levels = 1) {
  const auto start = std::chrono::steady_clock::now();
  const double dx = 1.0 / cells;
  Material<2> material;
  material.density = in.density;
  material.lame = constitutive::Lame::from_youngs_poisson(in.youngs, in.poisson);
  material.elastic = constitutive::NeoHookean<2>{material.lame.mu, material.lame.lambda};
  const AxisAligned field{in.amplitude, in.density, material.lame.mu, material.lame.lambda,
                          std::sqrt(in.youngs / in.density)};

  MpmState<2> state;
  // Images within 5 cells of the coarsest level (> 2 x the widest stencil radius: 2 dx for the
  // cubic B-spline, 1.25 dx for a coarse particle's box); the domain on whole coarse cells.
  const double dx0 = dx * (1 << (levels - 1));
  const double band = 5.0 * dx0;
  const double margin = band + 4.0 * dx0;
  state.grid = SparseGrid<2>(Vec<2>::Constant(-margin), Vec<2>::Constant(1.0 + margin), dx);
  state.kernel = kernel;
  const int ppc = 4;
  const double volume = geometry::particle_volume<2>(dx, ppc);
  solid::add_solid_channels(state.particles);
  std::vector<Vec<2>>& reference = reference_positions(state.particles);
  const std::vector<Vec<2>> seeds = geometry::seed_box<2>(Vec<2>::Zero(), Vec<2>::Ones(), dx, ppc, 0.0, 1);
  auto add = [&](const Vec<2>& X, double v) {
    state.particles.push_back(X, field.velocity(X, 0.0), in.density * v, v, 0);
    state.particles.C.back() = field.velocity_gradient(X, 0.0);
    reference.back() = X;
  };
  if (levels == 1) {
    for (const Vec<2>& X : seeds) add(X, volume);
  } else {
    SceneSettings<2> settings;
    settings.domain_lo = Vec<2>::Constant(-margin);
    settings.domain_hi = Vec<2>::Constant(1.0 + margin);
    settings.dx = dx;
    adaptive::RefinementSettings<2> refinement;
    refinement.levels = levels;
    refinement.follow_particles = false;
    for (const double shift : {-1.0, 0.0, 1.0}) {
      adaptive::RefinementRegion<2> stripe;
      stripe.lo = Vec<2>(shift + 0.25, -margin);
      stripe.hi = Vec<2>(shift + 0.75, 1.0 + margin);
      stripe.level = levels - 1;
      refinement.regions.push_back(stripe);
    }
    state.adaptive.emplace(adaptive::build_tree(refinement, settings, {}));
    std::vector<std::uint16_t>& type = adaptive::add_level_channel(state.particles, state.adaptive->tree());
    const auto levelled = adaptive::match_particles_to_leaves(state.adaptive->tree(), seeds, volume, 2);
    for (std::size_t i = 0; i < levelled.x.size(); ++i) {
      add(levelled.x[i], levelled.volume[i]);
      type.back() = levelled.level[i];
    }
  }

  const int steps = static_cast<int>(std::ceil(in.end_time / (in.wave_cfl * dx / material.wave_speed())));
  stages::TimeStepControl<2>::Settings dt;
  dt.wave_speed = material.wave_speed();
  dt.wave_cfl = in.wave_cfl;
  dt.max_dt = in.end_time / steps;  // equal steps, the last one ends at T
  Pipeline<MpmState<2>> pipeline(particle_fields(state.particles));
  pipeline.add(std::make_unique<stages::TimeStepControl<2>>(dt));
  pipeline.add(std::make_unique<PeriodicImages>(band));
  pipeline.add(std::make_unique<stages::SortParticles<2>>());
  pipeline.add(std::make_unique<stages::ParticlesToGrid<2>>());
  pipeline.add(std::make_unique<stages::StressForces<2>>(std::vector<Material<2>>{material}));
  pipeline.add(std::make_unique<ManufacturedBodyForce>(field));
  pipeline.add(std::make_unique<stages::GridVelocityUpdate<2>>(true));
  if (levels > 1) pipeline.add(std::make_unique<stages::GhostVelocities<2>>());
  pipeline.add(std::make_unique<stages::GridToParticles<2>>(solid::kElasticF));

  double space_time = 0.0, stripe = 0.0;
  for (int n = 0; n < steps; ++n) {
    mpm::step_towards(state, pipeline, in.end_time);
    space_time = std::max(space_time, max_error(state, field, nullptr, &stripe));
  }
  double rms = 0.0;
  const double final_max = max_error(state, field, &rms);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {{cells, dx, final_max, seconds},
          {cells, dx, rms, seconds},
          {cells, dx, space_time, seconds},
          {cells, dx, stripe, seconds}};
}

struct Sweep {
  std::vector<Level> final_max, final_rms, space_time_max;
};

Sweep sweep(const Kernel& kernel, const MmsSettings& settings) {
  Sweep s;
  for (int cells : {8, 16, 32, 64}) {
    const MmsErrors e = run_mms(cells, kernel, settings);
    s.final_max.push_back(e.final_max);
    s.final_rms.push_back(e.final_rms);
    s.space_time_max.push_back(e.space_time_max);
  }
  char name[96];
  std::snprintf(name, sizeof name, "axis-aligned MMS, A = %g m, %s", settings.amplitude, kernel_name(kernel).c_str());
  verification::print_table(std::string(name) + ", max_p |e_p(T)| / A", s.final_max);
  verification::print_table(std::string(name) + ", rms_p |e_p(T)| / A", s.final_rms);
  verification::print_table(std::string(name) + ", max_n max_p |e_p(t^n)| / A", s.space_time_max);
  return s;
}

}  // namespace

// Measured orders and finest-level errors are in docs/verification.md; the bounds below leave
// a margin of about 0.3 in the order and 1.5x in the error.
TEST_CASE("axis-aligned MMS, small deformation (A = 0.01 m): second order with the cubic B-spline") {
  MmsSettings settings;
  settings.amplitude = 0.01;
  const Sweep cubic = sweep(CubicBSpline{}, settings);  // measured 2.13, 2.14, 2.16
  CHECK(verification::observed_order(cubic.final_max) > 1.8);
  CHECK(verification::observed_order(cubic.final_rms) > 1.8);
  CHECK(verification::observed_order(cubic.space_time_max) > 1.8);
  CHECK(cubic.space_time_max.back().error < 2e-3);  // measured 1.35e-3
  // The quadratic B-spline and uGIMP converge more slowly and their ratio falls per level
  // (cell-crossing quadrature error, docs/verification.md): no order asserted, errors bounded.
  const Sweep quadratic = sweep(QuadraticBSpline{}, settings);
  CHECK(quadratic.space_time_max.back().error < 5.5e-3);  // measured 3.70e-3, order 1.64
  const Sweep ugimp = sweep(UGimp{0.25}, settings);
  CHECK(ugimp.space_time_max.back().error < 4.5e-3);  // measured 3.10e-3, order 1.48
}

// At the paper's amplitude F_xx spans [0.69, 1.31] and particles cross up to 3 cells at 64
// cells: the quadratic and uGIMP errors reach a plateau near 3% of A; the cubic still
// converges, more slowly than O(dx^2).
TEST_CASE("axis-aligned MMS, the paper's amplitude (A = 0.05 m): bounded error") {
  const MmsSettings settings;
  const Sweep cubic = sweep(CubicBSpline{}, settings);
  CHECK(verification::observed_order(cubic.final_rms) > 1.5);  // measured 1.97
  CHECK(cubic.space_time_max.back().error < 8e-3);             // measured 5.24e-3
  const Sweep quadratic = sweep(QuadraticBSpline{}, settings);
  CHECK(quadratic.space_time_max.back().error < 4.5e-2);  // measured 3.22e-2
  const Sweep ugimp = sweep(UGimp{0.25}, settings);
  CHECK(ugimp.space_time_max.back().error < 3.5e-2);  // measured 2.42e-2
}

// On an adaptive grid of two levels refined in a stripe (fine for 0.25 < X < 0.75, twice as
// coarse outside; each particle of its leaf's type, its box half a cell of its level), against
// uGIMP with the same boxes (h = 1/4) on uniform grids, space-time max error (docs/verification.md
// section 5 has the tables). Over all particles the coarse part sets the error: measured 0.88x
// to 0.98x the uniform coarse grid's, order 1.45 (the uniform uGIMP's 1.48). In the stripe the
// error approaches the uniform fine grid's there: 1.87x, 1.32x, 1.10x at 32, 64, 128 cells.
TEST_CASE(
    "axis-aligned MMS on an adaptive grid refined in a stripe (A = 0.01 m): the coarse error outside, the fine one in "
    "the stripe") {
  MmsSettings settings;
  settings.amplitude = 0.01;
  std::vector<Level> all, stripe, uniform_all, uniform_stripe;
  for (int cells : {8, 16, 32, 64, 128}) {
    const MmsErrors u = run_mms(cells, UGimp{0.25}, settings);
    uniform_all.push_back(u.space_time_max);
    uniform_stripe.push_back(u.stripe_max);
    if (cells == 8) continue;
    const MmsErrors a = run_mms(cells, UGimp{0.25}, settings, 2);
    all.push_back(a.space_time_max);
    stripe.push_back(a.stripe_max);
  }
  const std::string name = "axis-aligned MMS, A = 0.01 m, max_n max_p |e_p(t^n)| / A, ";
  verification::print_table(name + "adaptive (2 levels, fine in 0.25 < X < 0.75; cells = finest), all particles", all);
  verification::print_table(name + "adaptive, the particles of the stripe", stripe);
  verification::print_table(name + "uniform uGIMP h = 1/4, all particles", uniform_all);
  verification::print_table(name + "uniform uGIMP h = 1/4, the particles of the stripe", uniform_stripe);
  CHECK(verification::observed_order(all) > 1.25);    // measured 1.45
  CHECK(verification::observed_order(stripe) > 1.2);  // measured 1.38
  for (std::size_t i = 0; i < all.size(); ++i) {
    CAPTURE(all[i].cells);
    CHECK(all[i].error < 1.1 * uniform_all[i].error);  // the coarse grid (cells / 2)
  }
  CHECK(stripe.back().error < 1.2 * uniform_stripe.back().error);  // finest level
}
