#pragma once
//! Drucker-Prager return map for granular materials (Gao et al. 2017 sec. 4.2.1; Klar et al.
//! 2016) with the volume correction of Tampubolon et al. 2017.
//!
//! Yield function on the Kirchhoff stress tau of the Hencky StVK model (hencky_stvk.h):
//!   y(tau) = ||dev tau||_F + alpha tr(tau) - k <= 0,
//!   alpha = sqrt(2/3) 2 sin(phi) / (3 - sin(phi)),   k = sqrt(2/3) 6 c cos(phi) / (3 - sin(phi)),
//! the cone circumscribing the Mohr-Coulomb surface of friction angle phi and cohesion c; its
//! apex lies at tr(tau) = k / alpha = 3 c cot(phi) (tension), at tr(tau) = 0 without cohesion.
//! 2D uses the same constants with the 2D deviator, as Klar et al. do.
//!
//! The map works on the principal Hencky strain eps = log|sigma(Fe)|, where tau is linear:
//! dev tau = 2 mu dev eps, tr tau = (d lambda + 2 mu) tr eps. The flow is non-associative and
//! purely deviatoric (tr eps is kept), so three cases remain:
//!   I   y <= 0: elastic, Fe unchanged (or absorbing the stored correction, see below);
//!   II  the trial stress is beyond the apex (no deviatoric projection reaches the cone):
//!       eps = apex (expansion, the grains separate and carry no shear);
//!   III eps -= dgamma dev(eps)/||dev eps||, dgamma = y / (2 mu): back onto the cone.
//!
//! Volume correction. Case II discards volumetric strain, so under expansion the rest volume
//! of the material grows; compressing it back would then meet elastic resistance and the
//! material would gain volume. The per-particle state `plastic` = v stores the log volume
//! removed in case II, and v/d is added back to every trial strain: the material must first
//! be compressed by v before it develops pressure. With this, log det Fe + v equals the log of
//! the total volume change at all times (all three cases keep tr eps + v).
//!
//! Dilatancy (optional; Roux & Radjai 1998, Pailha & Pouliquen 2009 eq. 2.4-2.5). With a
//! dilatancy coefficient K > 0 and a critical packing phi_c, the grains' volume fraction phi
//! sets a dilatancy angle and adds it to the friction:
//!   tan psi = K (phi - phi_c),   mu = mu_cone + tan psi,   tr d eps^p = tan psi gamma_dot dt,
//! where mu_cone = alpha d / sqrt(2) is the cone's own ratio of shear stress to pressure in
//! simple shear (||dev tau|| = sqrt(2) tau_xy, tr tau = d p) and gamma_dot dt = sqrt(2) dgamma
//! the engineering shear strain of the plastic step. A dense packing (phi > phi_c) is
//! stronger and dilates as it yields, a loose one weaker and contracting, both toward phi_c
//! (the critical state). The plastic volume change is elastic compression of the returned
//! state (tr eps drops by sqrt(2) tan psi dgamma), so a confined dense sample builds pressure
//! and a loose one loses it. phi comes from the per-particle rest packing phi_r, the packing
//! at F^E = I (solid_channels.h): phi = phi_r / det F^E_trial; the map updates phi_r by
//! det F^E_new / det F^E_trial (the total volume does not change within the map), which keeps
//! phi_r / det F^E the true packing in all three cases.
//!
//! Rate-dependent friction (optional): with mu_2 > mu_cone the friction grows with a
//! dimensionless shear rate X of the plastic flow,
//!   mu(X) = mu_cone + (mu_2 - mu_cone) X / (X + X_0),
//! either the viscous number of dense suspensions, X = J = eta_f gamma_dot / P (Boyer,
//! Guazzelli & Pouliquen 2011, eq. 6), or the inertial number of dry grains,
//! X = I = d gamma_dot / sqrt(P / rho_s) (GDR MiDi 2004; Jop, Forterre & Pouliquen 2006, eq. 2),
//! gamma_dot = sqrt(2) dgamma / dt, P = -tr tau / d of the returned state (P <= 0: X = inf).
//! Case III then solves y(dgamma) = 0 with the friction of its own dgamma (y decreases
//! monotonically in dgamma: bisection); a slow flow (X -> 0) is the rate-independent map, a
//! flow at vanishing pressure meets mu_2. With the inertial number a thin, fast layer (a
//! collapse's front) is the most frictional part of the flow.
//!
//! Suspension (optional, with mu(J) and dilatancy): below jamming the grains also flow as a
//! dense suspension (Boyer, Guazzelli & Pouliquen 2011). Their phi(J) = phi_c / (1 + sqrt J)
//! gives the packing a viscous number J(phi) = (phi_c / phi - 1)^2, the particle pressure
//! P = eta_f gamma_dot / J and the shear stress mu(J) P (eq. 6, with the hydrodynamic terms
//! J + 5/2 phi_c sqrt J): a viscosity
//!   eta_v(phi) = eta_f (mu_c(J) / J + 1 + 5/2 phi_c / sqrt J),  mu_c = mu_1 + (mu_2 - mu_1) / (1 + J_0 / J),
//! about 210 eta_f at phi = 0.55, phi_c = 0.58 (2D, 28-30 deg). J is held at or above j_min
//! (default 1e-3: eta_v about 550 eta_f in 2D, 740 in 3D), also at and above phi_c, so eta_v is
//! continuous in phi: closer to jamming the frictional skeleton carries the flow. The sand
//! resists shear with the larger of its frictional and its viscous strength,
//! ||dev tau|| = max(alpha (-tr tau) + k, 2 eta_v dgamma / dt) while it flows, which is how a
//! liquefied sand (no contact pressure, case II) keeps a shear stress. Both strengths grow
//! with dgamma, so dgamma is the smaller of the two roots; the viscous one is closed form,
//!   2 mu (||dev eps|| - dgamma) = 2 eta_v dgamma / dt  ->  dgamma / ||dev eps|| = mu dt / (mu dt + eta_v),
//! an implicit (backward Euler) viscous update: the stress never exceeds the elastic trial, so
//! the elastic wave's time step stays stable at any eta_v. Over steps longer than the Maxwell
//! time eta_v / mu a steady shear reaches dev tau = 2 eta_v D. The particle pressure itself is
//! not added to the grains' stress.
#include <mpm/constitutive/hencky_stvk.h>
#include <mpm/constitutive/lame.h>
#include <mpm/core/error.h>
#include <mpm/core/types.h>
#include <mpm/math/svd.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

namespace mpm::plasticity {

template <int dim>
class DruckerPrager {
public:
  static constexpr std::string_view name = "drucker_prager";

  //! What the sand does beyond the cone: dilatancy and rate-dependent friction (both off by
  //! default).
  struct Flow {
    double dilatancy = 0.0;         //!< K of tan psi = K (phi - phi_c) [-]; 0: none
    double critical_packing = 0.6;  //!< phi_c [-], in (0, 1)
    double mu_2 = 0.0;              //!< mu(X) at large X [-]; 0: rate independent, else >= mu_cone
    double j_0 = 0.005;             //!< X_0 [-] > 0: J_0, or I_0 for the inertial number
    double viscosity = 0.0;         //!< eta_f of J [Pa s]; > 0 selects the viscous number
    double grain_diameter = 0.0;    //!< d of I [m]; > 0 selects the inertial number
    double grain_density = 0.0;     //!< rho_s of I [kg/m^3] > 0 with grain_diameter
    bool suspension = false;        //!< Boyer's suspension viscosity below jamming (needs J and K > 0)
    double j_min = 1e-3;            //!< the smallest J of the suspension viscosity [-], in (0, 1)
    bool inertial() const { return grain_diameter > 0.0; }
  };

  //! friction_angle [deg] in [0, 90), cohesion [Pa] >= 0; lame of the Hencky StVK elasticity.
  DruckerPrager(double friction_angle, double cohesion, const constitutive::Lame& lame, Flow flow = {})
      : elastic_{lame.mu, lame.lambda}, flow_(flow) {
    verify<InputError>(flow.dilatancy >= 0.0, "Drucker-Prager dilatancy coefficient " + std::to_string(flow.dilatancy) +
                                                  ": expected a value >= 0");
    verify<InputError>(
        flow.critical_packing > 0.0 && flow.critical_packing < 1.0,
        "Drucker-Prager critical packing " + std::to_string(flow.critical_packing) + ": expected a value in (0, 1)");
    verify<InputError>(
        friction_angle >= 0.0 && friction_angle < 90.0,
        "Drucker-Prager friction angle " + std::to_string(friction_angle) + " deg: expected a value in [0, 90)");
    verify<InputError>(cohesion >= 0.0,
                       "Drucker-Prager cohesion " + std::to_string(cohesion) + " Pa: expected a value >= 0");
    const double sin_phi = std::sin(friction_angle * std::numbers::pi / 180.0);
    const double cos_phi = std::cos(friction_angle * std::numbers::pi / 180.0);
    alpha_ = std::sqrt(2.0 / 3.0) * 2.0 * sin_phi / (3.0 - sin_phi);
    k_ = std::sqrt(2.0 / 3.0) * 6.0 * cohesion * cos_phi / (3.0 - sin_phi);
    if (flow.mu_2 != 0.0) {
      verify<InputError>(flow.mu_2 >= friction(), "Drucker-Prager mu_2 " + std::to_string(flow.mu_2) +
                                                      ": expected a value >= the static friction mu_1 = " +
                                                      std::to_string(friction()) + " of the friction angle");
      verify<InputError>(flow.j_0 > 0.0, std::string("Drucker-Prager ") + (flow.inertial() ? "I_0 " : "J_0 ") +
                                             std::to_string(flow.j_0) + ": expected > 0");
      if (flow.inertial())
        verify<InputError>(flow.grain_density > 0.0 && flow.viscosity == 0.0,
                           "Drucker-Prager inertial number: the grain density " + std::to_string(flow.grain_density) +
                               " kg/m^3 must be > 0 and no viscosity given");
      else
        verify<InputError>(flow.viscosity > 0.0,
                           "Drucker-Prager viscosity " + std::to_string(flow.viscosity) + " Pa s: expected > 0");
    }
    if (flow.suspension) {
      verify<InputError>(flow.mu_2 != 0.0 && !flow.inertial() && flow.dilatancy > 0.0,
                         "Drucker-Prager suspension: needs mu(J) (mu_2, viscosity) and dilatancy (its critical "
                         "packing)");
      verify<InputError>(flow.j_min > 0.0 && flow.j_min < 1.0,
                         "Drucker-Prager j_min " + std::to_string(flow.j_min) + ": expected a value in (0, 1)");
    }
  }

  //! mu_cone = alpha d / sqrt(2): the static friction, shear stress over pressure in simple shear.
  double friction() const { return alpha_ * dim / std::numbers::sqrt2; }
  //! The cone's alpha and k of y(tau) above (the CUDA back-end's copy of the map reads them).
  double cone_alpha() const { return alpha_; }
  double cone_k() const { return k_; }

  //! y of the Kirchhoff stress of Fe [Pa]; <= 0 is admissible.
  double yield_function(const Mat<dim>& Fe) const {
    return yield(elastic_.principal_kirchhoff(Hencky::principal_strain(math::svd(Fe).sigma)), alpha_);
  }

  double modulus_scale(double /*plastic*/) const { return 1.0; }

  //! Whether the friction and flow depend on the packing (K > 0); the return map then calls
  //! the overload with the rest packing.
  bool dilatant() const { return flow_.dilatancy > 0.0; }
  //! Whether the friction depends on the shear rate (mu_2 set); the map then needs dt.
  bool rate_dependent() const { return flow_.mu_2 > 0.0; }
  const Flow& flow() const { return flow_; }

  //! The suspension viscosity eta_v [Pa s] at the packing phi (see above; 0 without suspension).
  double suspension_viscosity(double phi) const {
    if (!flow_.suspension) return 0.0;
    const double phi_c = flow_.critical_packing;
    const double J = phi < phi_c ? std::max((phi_c / phi - 1.0) * (phi_c / phi - 1.0), flow_.j_min) : flow_.j_min;
    const double mu_c = friction() + (flow_.mu_2 - friction()) / (1.0 + flow_.j_0 / J);
    return flow_.viscosity * (mu_c / J + 1.0 + 2.5 * phi_c / std::sqrt(J));
  }

  //! Projects Fe onto the admissible set and updates the volume correction `plastic` (log
  //! volume, >= 0). Returns whether Fe changed. A changed Fe has positive singular values.
  //! `result`, when given, receives the SVD of the Fe left (the trial's when unchanged).
  //! Without a packing the map is that of K = 0.
  bool project(Mat<dim>& Fe, double& plastic, math::Svd<dim>* result = nullptr) const {
    return project(Fe, plastic, nullptr, 0.0, result);
  }

  //! The same with dilatancy (`rest_packing` phi_r, see above, is read and updated; nullptr:
  //! K = 0) and the rate dependence over a step dt [s] (0: rate independent).
  bool project(Mat<dim>& Fe, double& plastic, double* rest_packing, double dt, math::Svd<dim>* result = nullptr) const {
    return project(Fe, math::svd(Fe), plastic, rest_packing, dt, result);
  }

  //! The same given f = math::svd(Fe) (stages::ReturnMap takes the SVDs of several at once);
  //! `log_sigma`, when given, receives the log of the result's singular values (the map's
  //! principal strain, of which the Hencky stress is linear: HenckyStVK::kirchhoff).
  bool project(Mat<dim>& Fe, math::Svd<dim> f, double& plastic, double* rest_packing, double dt,
               math::Svd<dim>* result = nullptr, Vec<dim>* log_sigma = nullptr) const {
    const Vec<dim> strain = Hencky::principal_strain(f.sigma);
    const Vec<dim> eps = strain + Vec<dim>::Constant(plastic / dim);
    const double trace = eps.sum();
    const double bulk = dim * elastic_.lambda + 2.0 * elastic_.mu;  // tr tau / tr eps
    double alpha = alpha_, tan_psi = 0.0;
    double viscous_share = 1.0;  // dgamma / ||dev eps|| of the viscous strength alone
    const Vec<dim> dev = eps - Vec<dim>::Constant(trace / dim);
    if (rest_packing && dilatant()) {
      const double phi = *rest_packing * std::exp(-strain.sum());
      tan_psi = flow_.dilatancy * (phi - flow_.critical_packing);
      alpha = std::max(alpha_ + tan_psi * std::numbers::sqrt2 / dim, 0.0);  // mu_cone + tan psi
      if (flow_.suspension && dt > 0.0) {
        const double relax = elastic_.mu * dt;
        viscous_share = relax / (relax + suspension_viscosity(phi));
      }
    }
    Vec<dim> H = eps;
    const Vec<dim> viscous_dev = (1.0 - viscous_share) * dev;  // what a suspension keeps at the apex
    if (alpha > 0.0 && alpha * bulk * trace >= k_) {           // II: to the apex, store the excess
      plastic = to_apex(H, trace, alpha, bulk, viscous_dev);
    } else {
      const double y = yield(elastic_.principal_kirchhoff(eps), alpha);
      if (y <= 0.0 && plastic == 0.0) {  // I, nothing stored to absorb
        if (result) *result = f;
        if (log_sigma) *log_sigma = strain;
        return false;
      }
      plastic = 0.0;
      if (y > 0.0) {  // III
        const double dev_norm = dev.norm();
        // y falls by 2 mu for each unit of dgamma and by alpha bulk sqrt(2) tan psi through
        // the plastic volume change; where that does not reach the cone before the deviator
        // is spent (strong contraction), all shear goes and the volume change with it.
        const double slope = 2.0 * elastic_.mu + alpha * bulk * std::numbers::sqrt2 * tan_psi;  // -dy/ddgamma
        double share = slope > 0.0 && y < slope * dev_norm ? y / (slope * dev_norm) : 1.0;      // dgamma / ||dev||
        if (rate_dependent() && dt > 0.0) {
          const auto friction_at = [&](double dgamma) { return alpha + rate_friction(dgamma, trace, tan_psi, dt); };
          share = std::min(rate_dependent_share(dev_norm, trace, tan_psi, friction_at), viscous_share);
          alpha = friction_at(share * dev_norm);
        }
        H -= share * dev;
        if (tan_psi != 0.0) {
          H -= Vec<dim>::Constant(std::numbers::sqrt2 * tan_psi * share * dev_norm / dim);
          if (const double t = H.sum(); alpha > 0.0 && alpha * bulk * t > k_)
            plastic = to_apex(H, t, alpha, bulk, viscous_dev);
        }
      }
    }
    if (rest_packing && dilatant()) *rest_packing *= std::exp(H.sum() - strain.sum());
    f.sigma = Hencky::principal_stretch(H);
    Fe = math::scaled_product<dim>(f.U, f.sigma, f.V);
    if (result) *result = f;
    if (log_sigma) *log_sigma = H;
    return true;
  }

private:
  using Hencky = constitutive::HenckyStVK<dim>;

  double yield(const Vec<dim>& tau, double alpha) const {
    const double trace = tau.sum();
    return (tau - Vec<dim>::Constant(trace / dim)).norm() + alpha * trace - k_;
  }

  //! The cone's alpha that mu(X) adds at the plastic strain dgamma of a step dt [-].
  double rate_friction(double dgamma, double trace, double tan_psi, double dt) const {
    const double bulk = dim * elastic_.lambda + 2.0 * elastic_.mu;
    const double pressure = -bulk * (trace - std::numbers::sqrt2 * tan_psi * dgamma) / dim;
    const double gamma_dot = std::numbers::sqrt2 * dgamma / dt;
    // X / (X + X_0) as a / (a + X_0 P^m), 1 where P <= 0:
    //   J: a = eta gamma_dot, m = 1;  I: a = d gamma_dot sqrt(rho_s), m = 1/2.
    double share = 1.0;
    if (pressure > 0.0) {
      const double a = flow_.inertial() ? flow_.grain_diameter * gamma_dot * std::sqrt(flow_.grain_density)
                                        : flow_.viscosity * gamma_dot;
      share = a / (a + flow_.j_0 * (flow_.inertial() ? std::sqrt(pressure) : pressure));
    }
    return (flow_.mu_2 - friction()) * share * std::numbers::sqrt2 / dim;
  }

  //! Case III with mu(J): dgamma / ||dev|| in [0, 1] where y(dgamma) = 0 (y falls
  //! monotonically in dgamma: 2 mu per unit, and alpha(dgamma) grows while tr tau < 0), or 1
  //! where the deviator is spent first. Bisection to round-off.
  template <class FrictionAt>
  double rate_dependent_share(double dev_norm, double trace, double tan_psi, const FrictionAt& friction_at) const {
    const double bulk = dim * elastic_.lambda + 2.0 * elastic_.mu;
    const auto y = [&](double share) {
      const double dgamma = share * dev_norm;
      return 2.0 * elastic_.mu * (dev_norm - dgamma) +
             friction_at(dgamma) * bulk * (trace - std::numbers::sqrt2 * tan_psi * dgamma) - k_;
    };
    if (y(1.0) >= 0.0) return 1.0;
    double lo = 0.0, hi = 1.0;
    for (int n = 0; n < 60 && hi - lo > 1e-15; ++n) (y(0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
    return 0.5 * (lo + hi);
  }

  //! Case II: H becomes the apex plus the deviator a suspension keeps (zero without one);
  //! returns the log volume it discards (the new correction v).
  double to_apex(Vec<dim>& H, double trace, double alpha, double bulk, const Vec<dim>& viscous_dev) const {
    const double apex_trace = k_ / (alpha * bulk);
    H = viscous_dev + Vec<dim>::Constant(apex_trace / dim);
    return std::max(trace - apex_trace, 0.0);
  }

  Hencky elastic_;
  double alpha_ = 0.0;  //!< friction coefficient [-]
  double k_ = 0.0;      //!< cohesive strength [Pa]
  Flow flow_;
};

}  // namespace mpm::plasticity
