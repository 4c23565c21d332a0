// Backward Euler on the grid (Stomakhin et al. 2013 sec. 9; Zhu et al. sec. 6, eq. 12-19).
//
// Unknown: the node velocities v at t + dt. With the nodes moved to x_i + dt v_i, particle
// p deforms to F_p(v) = F_p^n + dt G_p(v), G_p = sum_i v_i grad w_ip^T F_p^n, and the step
// minimises the incremental potential
//   E(v) = sum_i m_i |v_i - v_i^*|^2 / 2 + sum_p V_p^0 psi(F_p(v)),   v^* = v^n + dt g,
// whose stationarity g(v) = M (v - v^*) - dt f(v) = 0 is the implicit momentum balance
// (f the stress forces of the explicit step, evaluated at t + dt). Newton's method:
//   (M + dt^2 K) dv = -g,   K dv = -df[dv] = sum_p V_p^0 dP_p(dF_p) F_p^nT grad w_ip,
//   dF_p = dt G_p(dv)                                                  (eq. 14-15)
// solved by CG with the exact dP, or, where CG meets negative curvature (compression and
// inversion soften a body), with dP made positive semi-definite in principal space (eq. 16,
// Teran et al. 2005), which makes the system SPD; Jacobi preconditioner, the
// diagonal formed in closed form (eq. 17-19). Each system is solved to linear_tolerance (an
// inexact Newton step); a backtracking line search halves the step until E decreases.
//
// Particle domains (Zhu et al. sec. 4-6): a particle deforms with its corners,
// G_p = sum_alpha v_alpha grad_X w_alpha_p^T, where a corner moves with the grid,
// v_alpha = sum_i w_i(x_alpha) v_i, or, enriched, at a velocity of its own that is an unknown
// with its mass m_alpha and predicted velocity p_alpha / m_alpha + dt g (eq. 11); the forces are
// f_alpha = - sum_p V_p^0 P_p grad_X w_alpha_p, carried to the nodes by the same weights. The
// operator is the same sum with the differentials, so the solve and its checks are unchanged.
//
// Plastic materials: the return map acts inside the step, the stress at v is that of the
// returned state, tau(Z(F_p(v))) F_p(v)^-T (returned_stress below), so a stiff sediment
// flows at the rate its yield stress allows at any dt. (Projecting only after the solve, as
// Stomakhin et al. 2013 do, limits the plastic strain of a step to the elastic strain of the
// trial state: a stiff Drucker-Prager column then barely collapses at large steps.) That
// stress has no potential; the line search then decreases |g|^2_{M^-1} instead of E.
//
// Walls and colliders: the obstacle directions that the predicted velocity v^* meets
// (ColliderSet::free_directions) are fixed at the obstacle's velocity; Newton moves the free
// directions only (the operator, the preconditioner and g projected by the node's projector).
// After the solve the fixed components get back their predicted (approach) velocity and the
// obstacles' projection runs once more: it restores the fixed values and applies Coulomb
// friction from the approach speed, so the boundary stage after this one changes nothing.
#include <mpm/solid/stages/implicit_update.h>

#include <mpm/core/detail/transfer_loops.h>
#include <mpm/core/error.h>
#include <mpm/core/solve/conjugate_gradient.h>
#include <mpm/core/solve/gmres.h>
#include <mpm/core/transfer.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/return_map.h>

#include <tbb/parallel_for.h>

#include <cmath>
#include <iostream>
#include <sstream>
#include <utility>

namespace mpm::stages {

template <int dim>
ImplicitUpdate<dim>::ImplicitUpdate(std::vector<Material<dim>> materials, geometry::ColliderSet<dim> colliders,
                                    ImplicitSettings settings)
    : materials_(std::move(materials)), colliders_(std::move(colliders)), settings_(settings) {}

template <int dim>
std::vector<Diagnostic> ImplicitUpdate<dim>::diagnostics() const {
  return {{"newton_iterations", double(last_.newton_iterations)},
          {"linear_iterations", double(last_.linear_iterations)},
          {"newton_residual", last_.residual},
          {"newton_unconverged", double(unconverged_)}};
}

namespace {
template <int dim>
void for_each_particle(std::size_t n, const auto& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) body(p);
  });
}

template <int dim>
double kinetic(const std::vector<double>& mass, const std::vector<Vec<dim>>& v,
               const std::vector<Vec<dim>>& predicted) {
  double e = 0.0;
  for (std::size_t k = 0; k < mass.size(); ++k)
    if (mass[k] > 0.0) e += 0.5 * mass[k] * (v[k] - predicted[k]).squaredNorm();
  return e;
}
}  // namespace

template <int dim>
const std::vector<double>& ImplicitUpdate<dim>::unknown_mass(const MpmState<dim>& s) {
  mass_ = s.grid.mass;
  if (!s.domains) return mass_;
  const domains::ParticleDomains<dim>& d = *s.domains;
  const std::size_t nodes = s.grid.node_storage();
  mass_.resize(nodes + d.enriched.size(), 0.0);  // a slot per corner when any may be enriched
  for (std::size_t c = 0; c < d.enriched.size(); ++c)
    if (d.enriched[c]) mass_[nodes + c] = d.mass[c];
  return mass_;
}

template <int dim>
void ImplicitUpdate<dim>::material_rate(const MpmState<dim>& s, const std::vector<Vec<dim>>& v,
                                        std::vector<Mat<dim>>& G) {
  const Particles<dim>& P = s.particles;
  if (!s.domains) {
    const std::vector<Mat<dim>>& F = solid::elastic_F(P);
    node_field_gradient(P, s.buckets, s.kernel, s.grid, v, G);
    for_each_particle<dim>(P.size(), [&](std::size_t p) { G[p] = (G[p] * F[p]).eval(); });
    return;
  }
  const domains::ParticleDomains<dim>& d = *s.domains;
  domains::corners_from_nodes(d, s.kernel, s.grid, v, corner_velocity_);
  const std::size_t nodes = s.grid.node_storage();
  for (std::size_t c = 0; c < d.enriched.size(); ++c)
    if (d.enriched[c]) corner_velocity_[c] = v[nodes + c];
  G.resize(P.size());
  for_each_particle<dim>(P.size(), [&](std::size_t p) { G[p] = d.gradient(p, corner_velocity_); });
}

template <int dim>
void ImplicitUpdate<dim>::internal_forces(const MpmState<dim>& s, const std::vector<Mat<dim>>& S,
                                          std::vector<Vec<dim>>& out) {
  const Particles<dim>& P = s.particles;
  if (!s.domains) {
    const std::vector<Mat<dim>>& F = solid::elastic_F(P);
    kirchhoff_.resize(P.size());
    for_each_particle<dim>(P.size(), [&](std::size_t p) { kirchhoff_[p] = S[p] * F[p].transpose(); });
    stress_to_nodes(kirchhoff_, P, s.buckets, s.kernel, s.grid, out);
    return;
  }
  const domains::ParticleDomains<dim>& d = *s.domains;
  domains::corner_forces(d, S, corner_force_);
  domains::nodes_from_corners(d, s.kernel, s.grid, corner_force_, out);
  const std::size_t nodes = s.grid.node_storage();
  out.resize(nodes + d.enriched.size(), Vec<dim>::Zero());
  for (std::size_t c = 0; c < d.enriched.size(); ++c)
    if (d.enriched[c]) out[nodes + c] = corner_force_[c];
}

template <int dim>
double ImplicitUpdate<dim>::deform(const MpmState<dim>& s, const std::vector<Vec<dim>>& v, bool energy) {
  const Particles<dim>& P = s.particles;
  const std::vector<Mat<dim>>& F = solid::elastic_F(P);
  material_rate(s, v, grad_);
  trial_F_.resize(P.size());
  for_each_particle<dim>(P.size(), [&](std::size_t p) { trial_F_[p] = F[p] + s.dt * grad_[p]; });
  if (!energy) return 0.0;
  energy_.assign(P.size(), 0.0);
  const std::vector<double>& plastic = solid::plastic_state(P);
  for (std::size_t m = 0; m < materials_.size(); ++m)
    std::visit(
        [&](const auto& model, const auto& plasticity) {
          for_each_particle<dim>(P.size(), [&](std::size_t p) {
            if (P.material[p] == m)
              energy_[p] = P.volume0[p] * plasticity.modulus_scale(plastic[p]) * model.energy(trial_F_[p]);
          });
        },
        materials_[m].elastic, materials_[m].plasticity);
  double sum = 0.0;  // in index order: the same bits on every thread count
  for (const double e : energy_) sum += e;
  return sum;
}

namespace {
//! The stress and differential of a plastic particle at F^E_trial = U diag(sigma) V^T: the
//! return map Z inside the step, P~ = tau(Z(F_trial)) F_trial^-T = U diag(p~(sigma)) V^T,
//! p~_i = tau_i(Z(diag sigma)) / sigma_i, an isotropic function of F_trial. Its principal
//! Jacobian dp~/dsigma by central differences (the return maps are closed form but piecewise;
//! a non-associative flow makes the Jacobian non-symmetric: the Newton system is solved by
//! GMRES then); only when `jacobian`. `stress` gets P~.
template <int dim, class Elastic, class Plastic>
constitutive::StressDerivative<dim> returned_stress(const Elastic& elastic, const Plastic& plastic, double state,
                                                    const Mat<dim>& F, bool jacobian, Mat<dim>& stress) {
  constitutive::StressDerivative<dim> s{math::svd(F), {}};
  const auto principal = [&](const Vec<dim>& sigma) {
    Mat<dim> Fe = sigma.asDiagonal();
    double a = state;
    plastic.project(Fe, a);
    const Vec<dim> tau = plastic.modulus_scale(a) * (elastic.first_piola(Fe) * Fe.transpose()).diagonal();
    return Vec<dim>(tau.array() /
                    sigma.unaryExpr([](double x) { return constitutive::detail::safe_denominator(x); }).array());
  };
  const Vec<dim>& sigma = s.f.sigma;
  const Vec<dim> p = principal(sigma);
  stress = math::scaled_product<dim>(s.f.U, p, s.f.V);
  if (!jacobian) return s;
  Mat<dim> J;
  for (int j = 0; j < dim; ++j) {
    const double h = 1e-6 * std::max(std::abs(sigma(j)), 1e-3);
    Vec<dim> up = sigma, down = sigma;
    up(j) += h;
    down(j) -= h;
    J.col(j) = (principal(up) - principal(down)) / (2.0 * h);
  }
  s.d.dp_dsigma = J;
  s.d.sym.setZero();
  s.d.skew.setZero();
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) {
      if (i == j) continue;
      const bool close = std::abs(sigma(i) - sigma(j)) <= 1e-6 * (std::abs(sigma(i)) + std::abs(sigma(j)));
      s.d.sym(i, j) = close ? J(i, i) - J(i, j) : (p(i) - p(j)) / (sigma(i) - sigma(j));
      s.d.skew(i, j) = (p(i) + p(j)) / constitutive::detail::safe_denominator(sigma(i) + sigma(j));
    }
  return s;
}
}  // namespace

template <int dim>
void ImplicitUpdate<dim>::linearise(const MpmState<dim>& s, bool derivatives, bool definite) {
  const Particles<dim>& P = s.particles;
  const std::vector<double>& plastic_state = solid::plastic_state(P);
  weighted_stress_.assign(P.size(), Mat<dim>::Zero());
  has_stress_.assign(P.size(), 0);
  if (derivatives) derivative_.resize(P.size());
  for (std::size_t m = 0; m < materials_.size(); ++m)
    std::visit(
        [&](const auto& model, const auto& plastic) {
          constexpr bool elastic = std::is_same_v<std::decay_t<decltype(plastic)>, plasticity::NoPlasticity>;
          for_each_particle<dim>(P.size(), [&](std::size_t p) {
            if (P.material[p] != m) return;
            has_stress_[p] = 1;
            Mat<dim> stress;
            if constexpr (!elastic) {
              const auto d = returned_stress<dim>(model, plastic, plastic_state[p], trial_F_[p], derivatives, stress);
              if (derivatives) {
                derivative_[p] = d;
                if (definite) {  // its symmetric part, made positive semi-definite
                  Mat<dim>& J = derivative_[p].d.dp_dsigma;
                  J = 0.5 * (J + J.transpose()).eval();
                  constitutive::detail::make_positive_semidefinite(derivative_[p].d);
                }
              }
            } else if (derivatives) {
              derivative_[p] = constitutive::stress_derivative(model, trial_F_[p], definite);
              const math::Svd<dim>& f = derivative_[p].f;
              stress = math::scaled_product<dim>(f.U, model.principal_stress(f.sigma), f.V);
            } else {
              stress = model.first_piola(trial_F_[p]);
            }
            weighted_stress_[p] = P.volume0[p] * stress;
          });
        },
        materials_[m].elastic, materials_[m].plasticity);
}

template <int dim>
void ImplicitUpdate<dim>::collect_two_step_gradients(const MpmState<dim>& s) {
  two_step_.clear();
  if (!s.domains) return;
  domains::for_each_two_step_gradient<dim>(*s.domains, s.kernel, s.grid,
                                           [&](std::size_t p, Index node, const Vec<dim>& q) {
                                             if (node >= 0) two_step_.push_back({p, node, q});
                                           });
}

template <int dim>
void ImplicitUpdate<dim>::jacobi_diagonal(const MpmState<dim>& s, std::vector<Vec<dim>>& diagonal) {
  const Particles<dim>& P = s.particles;
  diagonal.assign(mass_.size(), Vec<dim>::Zero());
  // c e_a . dP(e_a q^T) q per component, q the reference gradient of the unknown's weight,
  // = c q^T B_a q with (B_a)_jk = dP(e_a e_k^T)_aj: dim^2 differentials per particle (in
  // parallel) instead of dim per node (a particle reaches 3^dim to 4^dim nodes).
  diagonal_form_.resize(P.size());
  for_each_particle<dim>(P.size(), [&](std::size_t p) {
    if (!has_stress_[p]) return;
    for (int a = 0; a < dim; ++a)
      for (int k = 0; k < dim; ++k)
        diagonal_form_[p][a].col(k) =
            derivative_[p].apply(Vec<dim>::Unit(a) * Vec<dim>::Unit(k).transpose()).row(a).transpose();
  });
  if (s.domains) {
    const domains::ParticleDomains<dim>& d = *s.domains;
    const auto add = [&](std::size_t p, const Vec<dim>& q, Vec<dim>& out) {
      if (!has_stress_[p]) return;
      const double c = s.dt * s.dt * P.volume0[p];
      for (int a = 0; a < dim; ++a) out[a] += c * q.dot(diagonal_form_[p][a] * q);
    };
    for (const TwoStepGradient& e : two_step_) add(e.particle, e.q, diagonal[e.node]);
    constexpr int K = domains::ParticleDomains<dim>::corners;
    for (std::size_t c = 0; c < d.enriched.size(); ++c)
      for (std::uint32_t k = d.sharing_begin[c]; d.enriched[c] && k != d.sharing_begin[c + 1]; ++k) {
        const std::size_t p = d.sharing[k] / K;
        add(p, d.weight_gradient(p, static_cast<int>(d.sharing[k] % K)), diagonal[s.grid.node_storage() + c]);
      }
  } else {
    jacobi_nodes(s, diagonal);
  }
  // A non-symmetric (plastic) system may have entries of K below zero: the mass alone there.
  for (std::size_t n = 0; n < mass_.size(); ++n) diagonal[n] = Vec<dim>::Constant(mass_[n]) + diagonal[n].cwiseMax(0.0);
}

template <int dim>
void ImplicitUpdate<dim>::jacobi_nodes(const MpmState<dim>& s, std::vector<Vec<dim>>& diagonal) const {
  const Particles<dim>& P = s.particles;
  const SparseGrid<dim>& g = s.grid;
  const std::vector<Mat<dim>>& F = solid::elastic_F(P);
  std::array<detail::ChannelView, dim> channels;
  for (int a = 0; a < dim; ++a) channels[a] = detail::component_view<dim>(diagonal, a);
  const double inv_dx = 1.0 / g.dx();
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::scatter<dim, dim>(
            g, s.buckets, channels, [&](std::uint32_t p, const detail::PatchFrame<dim>& f, double* patch) {
              if (!has_stress_[p]) return;
              detail::Stencil<dim, K::support> st;
              st.compute(k, f.cells(P.x[p]), f.origin);
              const Mat<dim> FT = inv_dx * F[p].transpose();
              const double c = s.dt * s.dt * P.volume0[p];
              st.for_each_node([&](int node, double, const Vec<dim>& grad, const Vec<dim>&) {
                const Vec<dim> q = FT * grad;  // grad_X w_ip, the reference-configuration gradient
                for (int a = 0; a < dim; ++a) patch[node * dim + a] += c * q.dot(diagonal_form_[p][a] * q);
              });
            });
      },
      s.kernel);
}

template <int dim>
double ImplicitUpdate<dim>::potential(const MpmState<dim>& s, const std::vector<Vec<dim>>& v,
                                      const std::vector<Vec<dim>>& predicted) {
  unknown_mass(s);
  return energy(s, v, predicted);
}

template <int dim>
double ImplicitUpdate<dim>::energy(const MpmState<dim>& s, const std::vector<Vec<dim>>& v,
                                   const std::vector<Vec<dim>>& predicted) {
  return deform(s, v, true) + kinetic(mass_, v, predicted);
}

template <int dim>
void ImplicitUpdate<dim>::gradient(const MpmState<dim>& s, const std::vector<Vec<dim>>& v,
                                   const std::vector<Vec<dim>>& predicted, std::vector<Vec<dim>>& out) {
  unknown_mass(s);
  deform(s, v, false);
  linearise(s, false, false);
  internal_forces(s, weighted_stress_, out);
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = mass_[k] > 0.0 ? Vec<dim>(mass_[k] * (v[k] - predicted[k]) - s.dt * out[k]) : Vec<dim>::Zero();
}

template <int dim>
void ImplicitUpdate<dim>::hessian_product(const MpmState<dim>& s, const std::vector<Vec<dim>>& v,
                                          const std::vector<Vec<dim>>& dv, std::vector<Vec<dim>>& out, bool definite) {
  unknown_mass(s);
  deform(s, v, false);
  linearise(s, true, definite);
  apply_hessian(s, dv, out);
}

template <int dim>
void ImplicitUpdate<dim>::preconditioner_diagonal(const MpmState<dim>& s, const std::vector<Vec<dim>>& v,
                                                  std::vector<Vec<dim>>& out, bool definite) {
  unknown_mass(s);
  collect_two_step_gradients(s);
  deform(s, v, false);
  linearise(s, true, definite);
  jacobi_diagonal(s, out);
}

template <int dim>
void ImplicitUpdate<dim>::apply_hessian(const MpmState<dim>& s, const std::vector<Vec<dim>>& dv,
                                        std::vector<Vec<dim>>& out) {
  const Particles<dim>& P = s.particles;
  material_rate(s, dv, grad_);
  differential_stress_.resize(P.size());
  for_each_particle<dim>(P.size(), [&](std::size_t p) {
    differential_stress_[p] =
        has_stress_[p] ? Mat<dim>(P.volume0[p] * derivative_[p].apply(s.dt * grad_[p])) : Mat<dim>::Zero();
  });
  internal_forces(s, differential_stress_, out);
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = mass_[k] > 0.0 ? Vec<dim>(mass_[k] * dv[k] - s.dt * out[k]) : Vec<dim>::Zero();
}

template <int dim>
void ImplicitUpdate<dim>::run(MpmState<dim>& s) {
  MPM_VERIFY(!s.adaptive, InputError, "solver 'implicit' runs on a uniform grid only (the scene is adaptive)");
  MPM_VERIFY(!s.domains || s.domains->point_count == 0, InputError,
             "solver 'implicit' with particle domains needs domains on every body (material points take no part "
             "in its solve)");
  SparseGrid<dim>& g = s.grid;
  momentum_to_velocity(g, s.transfer);
  const std::vector<double>& mass = unknown_mass(s);
  collect_two_step_gradients(s);  // the corners stay put through the solve
  const std::size_t n = mass.size(), nodes = g.node_storage();
  const double t = s.time + s.dt;
  // Unknown k: a node, or (k >= nodes) an enriched domain corner, a material point.
  domains::ParticleDomains<dim>* d = s.domains ? &*s.domains : nullptr;
  const auto position = [&](std::size_t k) { return k < nodes ? g.node_position(k) : d->x[k - nodes]; };
  const auto point = [&](std::size_t k) {
    return k < nodes ? geometry::ContactPoint::node : geometry::ContactPoint::material;
  };
  const auto start = [&](std::size_t k) {
    return k < nodes ? g.velocity[k] : Vec<dim>(d->momentum[k - nodes] / d->mass[k - nodes]);
  };

  // The predicted velocity, the free directions of every unknown and the initial iterate.
  std::vector<Vec<dim>> predicted(n, Vec<dim>::Zero()), v(n, Vec<dim>::Zero());
  std::vector<Mat<dim>> free(n, Mat<dim>::Zero());
  double total_mass = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    if (mass[k] <= 0.0) continue;
    total_mass += mass[k];
    predicted[k] = start(k) + s.dt * s.gravity;
    free[k] = colliders_.free_directions(position(k), t, predicted[k], point(k));
    // Free directions from v^n (near the answer for material at rest under gravity), the fixed
    // ones at the obstacle's values for v^*, which Newton then keeps.
    Vec<dim> fixed = predicted[k];
    colliders_.project(position(k), t, fixed, point(k));
    v[k] = free[k] * start(k) + (Mat<dim>::Identity() - free[k]) * fixed;
  }
  last_ = {};
  history_.clear();
  if (total_mass <= 0.0) return;
  // The mass-weighted rms of the velocity residual M^-1 g relative to that of the step's
  // velocities: max(rms(v^*), rms(v)) + |g| dt (a body at rest under gravity: its balance to
  // that accuracy; a stressed body released from rest: its new velocities v), with a floor for
  // a state without motion or gravity. Relative, so that small steps do not drop their gravity
  // increment as an error below an absolute tolerance.
  const auto rms = [&](const std::vector<Vec<dim>>& x) {
    double square = 0.0;
    for (std::size_t k = 0; k < n; ++k) square += mass[k] * x[k].squaredNorm();
    return std::sqrt(square / total_mass);
  };
  const double predicted_rms = rms(predicted);

  // Elastic materials: CG and a line search on E. With a return map
  // inside the step the stress has no potential and the Jacobian is not symmetric: GMRES
  // minimises |g + J dv|_{M^-1}, so its step descends on the merit |g|^2_{M^-1} / 2 that the
  // line search then uses.
  const bool plastic = any_plastic(materials_);
  std::vector<Vec<dim>> grad(n), dv(n), trial(n), diagonal;
  // The projected residual g at x from the stresses of the last linearise() at x.
  const auto residual_at = [&](const std::vector<Vec<dim>>& x, std::vector<Vec<dim>>& r) {
    internal_forces(s, weighted_stress_, r);
    for (std::size_t k = 0; k < n; ++k)
      r[k] = mass[k] > 0.0 ? Vec<dim>(free[k] * (mass[k] * (x[k] - predicted[k]) - s.dt * r[k])) : Vec<dim>::Zero();
  };
  const auto weighted_square = [&](const std::vector<Vec<dim>>& r) {
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k)
      if (mass[k] > 0.0) sum += r[k].squaredNorm() / mass[k];
    return 0.5 * sum;
  };
  const auto residual = [&](const std::vector<Vec<dim>>& r, const std::vector<Vec<dim>>& x) {
    const double scale = std::max(predicted_rms, rms(x)) + s.gravity.norm() * s.dt + 1e-12 * g.dx() / s.dt;
    return std::sqrt(2.0 * weighted_square(r) / total_mass) / scale;
  };
  const auto merit = [&](const std::vector<Vec<dim>>& x) {
    if (!plastic) return energy(s, x, predicted);
    deform(s, x, false);
    linearise(s, false, false);
    residual_at(x, merit_residual_);
    return weighted_square(merit_residual_);
  };
  const double initial = plastic ? 0.0 : energy(s, v, predicted);
  if (plastic) deform(s, v, false);
  linearise(s, true, false);
  const solve::SolveControl control{settings_.linear_tolerance, 0.0, settings_.max_linear_iterations};
  std::string stalled;
  // The system scaled by S = M^-1/2 (on the free directions): the Krylov solvers' residual
  // |S (b - A dv)| is then the velocity residual that Newton's test measures, also at the
  // light nodes on a body's edge. Jacobi on the scaled operator: m_k / D_k.
  const auto S = [&](const std::vector<Vec<dim>>& x, std::vector<Vec<dim>>& y) {
    y.resize(n);
    for (std::size_t k = 0; k < n; ++k)
      y[k] = mass[k] > 0.0 ? Vec<dim>(free[k] * x[k] / std::sqrt(mass[k])) : Vec<dim>::Zero();
  };
  const auto SAS = [&](const std::vector<Vec<dim>>& x, std::vector<Vec<dim>>& y) {
    S(x, trial);
    apply_hessian(s, trial, merit_residual_);
    S(merit_residual_, y);
  };
  const auto jacobi = [&](const std::vector<Vec<dim>>& r, std::vector<Vec<dim>>& z) {
    z.resize(n);
    for (std::size_t k = 0; k < n; ++k)
      z[k] =
          mass[k] > 0.0 ? Vec<dim>(free[k] * (free[k] * r[k]).cwiseQuotient(diagonal[k] / mass[k])) : Vec<dim>::Zero();
  };
  // dv from the differentials of the last linearise(); false when CG met negative curvature.
  const auto newton_step = [&] {
    jacobi_diagonal(s, diagonal);
    std::vector<Vec<dim>> rhs(n), y(n, Vec<dim>::Zero());
    for (std::size_t k = 0; k < n; ++k) rhs[k] = -grad[k];
    S(rhs, rhs);
    const solve::SolveResult solved =
        plastic ? solve::gmres(SAS, jacobi, rhs, y, control) : solve::conjugate_gradient(SAS, jacobi, rhs, y, control);
    last_.linear_iterations += solved.iterations;
    S(y, dv);
    return plastic || (!solved.breakdown && solve::dot(grad, dv) < 0.0);
  };
  // A line search along dv from v on the merit; true (and v moved) when it decreased. E near
  // a converged state is known to the round-off of psi near F = R (about 1e-16 / |F - R| of
  // it, 1e-11 at strains of 1e-5): where E rises by less than 1e-9 |E| the step is taken when
  // it lowers the residual instead.
  double energy = 0.0;
  const auto line_search = [&] {
    if (solve::dot(dv, dv) == 0.0) return false;  // no step: nothing to search
    double step = 1.0;
    for (int halvings = 0; halvings < 30; ++halvings, step *= 0.5) {
      for (std::size_t k = 0; k < n; ++k) trial[k] = v[k] + step * dv[k];
      const double e = merit(trial);
      bool lower = std::isfinite(e) && (plastic ? e < energy : e <= energy);
      if (!lower && !plastic && std::isfinite(e) && e <= energy + 1e-9 * std::abs(energy)) {
        linearise(s, false, false);
        residual_at(trial, merit_residual_);
        lower = weighted_square(merit_residual_) < weighted_square(grad);
      }
      if (lower) {
        energy = e;
        v.swap(trial);
        return true;
      }
    }
    return false;
  };
  while (true) {
    residual_at(v, grad);
    last_.residual = residual(grad, v);
    if (!std::isfinite(last_.residual)) {
      stalled = "the residual is not finite";
      break;
    }
    if (last_.newton_iterations == 0 && !plastic) history_.push_back(initial);
    if (last_.residual <= settings_.tolerance) {
      last_.converged = true;
      if (plastic) history_.push_back(weighted_square(grad));
      break;
    }
    if (last_.newton_iterations == settings_.max_newton_iterations) break;
    energy = plastic ? weighted_square(grad) : history_.back();
    if (plastic) history_.push_back(energy);
    // Elastic: the exact Hessian first (Newton's quadratic convergence wherever M + dt^2 K is
    // positive, as the mass term usually makes it); where CG meets negative curvature or the
    // step does not lower E, the Hessian made definite per particle (Teran et al. 2005).
    bool moved = newton_step() && line_search();
    if (!moved && !plastic) {
      deform(s, v, false);
      linearise(s, true, true);
      moved = newton_step() && line_search();
    }
    if (!moved) {
      stalled = plastic ? "the line search found no decrease of the residual"
                        : "the line search found no decrease of the incremental potential";
      break;
    }
    ++last_.newton_iterations;
    if (!plastic) history_.push_back(energy);
    linearise(s, true, false);  // at the accepted iterate, whose F merit() left in trial_F_
  }

  if (!last_.converged) {
    ++unconverged_;
    std::ostringstream why;
    why << "stage '" << name() << "': Newton did not converge in " << last_.newton_iterations << " iterations ("
        << (stalled.empty() ? "iteration cap" : stalled) << "; relative residual " << last_.residual << ", tolerance "
        << settings_.tolerance << ", " << last_.linear_iterations << " linear solver iterations) at t = " << s.time
        << " s, step " << s.step;
    if (settings_.on_failure == solve::OnFailure::stop || !std::isfinite(last_.residual))
      throw NumericalError(why.str());
    std::cerr << "warning: " << why.str() << "\n";
  }
  // Fixed components back to their approach velocity, then the obstacles' projection once more.
  // An enriched corner's velocity and FLIP increment go where DomainsFromGrid reads them.
  for (std::size_t k = 0; k < n; ++k) {
    if (mass[k] <= 0.0) continue;
    Vec<dim> out = v[k] + (Mat<dim>::Identity() - free[k]) * (predicted[k] - v[k]);
    colliders_.project(position(k), t, out, point(k));
    if (k < nodes) {
      g.velocity[k] = out;
    } else {
      d->force[k - nodes] = out - start(k);
      d->momentum[k - nodes] = out;
    }
  }
}

template class ImplicitUpdate<2>;
template class ImplicitUpdate<3>;

}  // namespace mpm::stages
