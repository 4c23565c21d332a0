// The two-step transfers through particle domains and their dynamic enrichment (Zhu et al.
// sec. 4-5, eq. 5-11; equations in mpm/domains/particle_domains.h). The corner sums run over
// the corners (each reads the particles that share it), so no two threads write one corner and
// the sums do not depend on the thread count.
#include <mpm/core/error.h>
#include <mpm/core/finite_guard.h>
#include <mpm/domains/surface_contact.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/domain_transfer.h>
#include <mpm/solid/stages/stress_forces.h>

#include <tbb/parallel_for.h>

namespace mpm::stages {

namespace {
//! The corner table indexes the particles by storage position: a stage that added, removed or
//! reordered particles would pair them with the wrong corners.
template <int dim>
void check_pairing(const domains::ParticleDomains<dim>& d, const Particles<dim>& P, const std::string& stage) {
  MPM_VERIFY(d.particle_count() == P.size(), Error,
             "stage '" + stage + "': " + std::to_string(P.size()) + " particles but domains for " +
                 std::to_string(d.particle_count()) + " (particles with domains are never added or removed)");
}
}  // namespace

template <int dim>
void DomainEnrichment<dim>::run(MpmState<dim>& s) {
  domains::ParticleDomains<dim>& d = *s.domains;
  check_pairing(d, std::as_const(s.particles), name());
  domains::mark_enrichment(d, solid::elastic_F(s.particles), explicit_step_);
  share_ = d.particle_count() ? static_cast<double>(d.enriched_particles) / d.particle_count() : 0.0;
}

template <int dim>
void DomainsToGrid<dim>::run(MpmState<dim>& s) {
  domains::ParticleDomains<dim>& d = *s.domains;
  const Particles<dim>& P = s.particles;
  check_pairing(d, P, name());
  const std::vector<Mat<dim>>& F = solid::elastic_F(P);
  if (forces_) {
    const std::vector<double>& plastic = solid::plastic_state(P);
    const std::vector<Mat<dim>>* cache = solid::stress_cache(P);
    // A domain's stress acts through its corners as V^0 P (eq. 8); a material point's as
    // standard MPM's V^0 tau at its own corner (its zero reference gradients keep it out of the
    // corner sums).
    weighted_stress_.resize(P.size());
    for (std::size_t m = 0; m < materials_.size(); ++m)
      std::visit(
          [&](const auto& model, const auto& plasticity) {
            using Plasticity = std::decay_t<decltype(plasticity)>;
            const bool cached = cache && !std::is_same_v<Plasticity, plasticity::NoPlasticity>;
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
              for (std::size_t p = r.begin(); p != r.end(); ++p) {
                if (P.material[p] != m) continue;
                if (d.is_point(p))
                  weighted_stress_[p] = weighted_kirchhoff(model, plasticity, P.volume0[p], F[p], plastic[p],
                                                           cached ? &(*cache)[p] : nullptr);
                else
                  weighted_stress_[p] = P.volume0[p] * model.first_piola(F[p]);
              }
            });
          },
          materials_[m].elastic, materials_[m].plasticity);
    check_finite(weighted_stress_, name(), "particle", "stress");
  }
  constexpr int K = domains::ParticleDomains<dim>::corners;
  d.mass.resize(d.corner_count());
  d.momentum.resize(d.corner_count());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, d.corner_count(), 4096), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      if (d.point[c]) {  // the particle's own m and m v, not a sum of K equal shares
        const std::size_t p = d.point_particle(c);
        d.mass[c] = P.mass[p];
        d.momentum[c] = P.mass[p] * P.v[p];
        continue;
      }
      double m = 0.0;
      Vec<dim> momentum = Vec<dim>::Zero();
      for (std::uint32_t k = d.sharing_begin[c]; k != d.sharing_begin[c + 1]; ++k) {
        const std::size_t p = d.sharing[k] / K;
        m += P.mass[p];
        momentum += P.mass[p] * P.v[p];
      }
      d.mass[c] = m / K;  // w_alpha_p = 1 / 2^dim
      d.momentum[c] = momentum / K;
    }
  });
  if (forces_)
    domains::corner_forces(d, weighted_stress_, d.force);
  else
    d.force.assign(d.corner_count(), Vec<dim>::Zero());
  domains::corners_to_grid(d, s.kernel, s.grid, name(), weighted_stress_);
}

template <int dim>
void DomainsFromGrid<dim>::run(MpmState<dim>& s) {
  domains::ParticleDomains<dim>& d = *s.domains;
  Particles<dim>& P = s.particles;
  check_pairing(d, std::as_const(P), name());
  std::vector<Mat<dim>>& F = solid::elastic_F(P);
  const bool flip = s.transfer.uses_old_velocity();
  const double a = flip ? s.transfer.flip_ratio : 0.0;
  domains::grid_to_corners(d, s.kernel, s.grid, flip);
  // The enriched corners' own update, with the colliders the boundary stage applies to nodes
  // (an implicit step has solved for them already).
  const double t = s.time + s.dt;
  if (!enriched_stepped_)
    domains::integrate_enriched<dim>(d, s.dt, s.gravity, [&](const Vec<dim>& x, Vec<dim>& v) {
      colliders_.project(x, t, v, geometry::ContactPoint::material);
    });
  // Enriched surfaces meet what the grid no longer keeps them from (surface_contact.h).
  if (contacts_ >= 0) contacts_ = domains::surface_contact(d, s.dt, d.contact_thickness).contacts;
  domains::advance_corners(d, s.dt);
  constexpr int K = domains::ParticleDomains<dim>::corners;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      Vec<dim> pic = Vec<dim>::Zero(), increment = Vec<dim>::Zero();
      for (const std::uint32_t c : d.corner_of[p]) {
        pic += d.momentum[c];  // the corner velocity after grid_to_corners
        increment += d.force[c];
      }
      pic /= K;
      P.v[p] = flip ? Vec<dim>(a * (P.v[p] + increment / K) + (1.0 - a) * pic) : pic;
      P.x[p] = d.centre(p);
      if (d.is_point(p))  // standard MPM: F = (I + dt grad v) F
        F[p] = (Mat<dim>::Identity() + s.dt * d.velocity_gradient[d.corner_of[p][0]]) * F[p];
      else
        F[p] = d.deformation(p);
    }
  });
  check_finite(P.v, name(), "particle", "velocity");
  check_finite(F, name(), "particle", "deformation gradient");
}

template class DomainEnrichment<2>;
template class DomainEnrichment<3>;
template class DomainsToGrid<2>;
template class DomainsToGrid<3>;
template class DomainsFromGrid<2>;
template class DomainsFromGrid<3>;

}  // namespace mpm::stages
