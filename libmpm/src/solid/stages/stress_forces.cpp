// Grid forces of the explicit step (paper sec. 3.2, eq. 1-2), by default in the p2g scatter:
//   f_i = - sum_p V_p^0 P(F_p^E) (F_p^E)^T grad w_ip = - sum_p V_p^0 tau_p grad w_ip,
// there added to the momentum as the impulse dt f_i (no force channel) unless FLIP needs the
// velocity before the forces; tau = P F^T is the Kirchhoff stress of the elastic part
// (multiplicative plasticity keeps all stress in F^E). The constitutive model is chosen per
// material by std::visit outside the particle loop. Precondition: particles sorted into
// buckets (stage 'sort').
// A plastic material's tau is the one the last return map left in the stress cache
// (solid_channels.h), computed from its SVD of F^E: one SVD per particle and step instead of
// two. Particles whose cached stress is unknown (the first step, after a merge or a switch of
// a grain) take it from F^E here, as do elastic materials: tau = U diag(p_i sigma_i) U^T from
// the SVD of F^E, four particles' SVDs at a time in 3D (math::for_each_svd).
// Where every particle carries a cache (all materials plastic), the unknown entries are filled
// in the cache itself and the scatter reads S_p = w_p tau_p from it (ParticleStress, w_p = V_p^0
// and the hardening's modulus scale): no per-particle copy of V^0 tau is formed and read back.
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/finite_guard.h>
#include <mpm/core/transfer.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/stress_forces.h>

#include <tbb/parallel_for.h>

#include <atomic>

#include <utility>

namespace mpm::stages {

namespace {
//! Whether a plasticity model scales the elastic moduli with its state (snow's hardening).
template <int dim, class Plasticity>
constexpr bool scales_moduli = !std::is_same_v<Plasticity, plasticity::NoPlasticity> &&
                               !std::is_same_v<Plasticity, plasticity::DruckerPrager<dim>> &&
                               !std::is_same_v<Plasticity, plasticity::VonMises<dim>>;
}  // namespace

template <int dim>
void StressForces<dim>::run(MpmState<dim>& s) {
  Particles<dim>& P = s.particles;
  const std::vector<Mat<dim>>& F = solid::elastic_F(std::as_const(P));
  const std::vector<double>& plastic = solid::plastic_state(std::as_const(P));
  std::vector<Mat<dim>>* cache = solid::stress_cache(P);
  // The scatter reads the cache itself where every particle has one (all materials plastic).
  bool in_cache = cache && fused() && !stress_free_particles_;
  bool weighted = false;  // some material's moduli scale with its state: weights V^0 times that
  for (const Material<dim>& m : materials_) {
    in_cache = in_cache && !std::holds_alternative<plasticity::NoPlasticity>(m.plasticity);
    weighted = weighted ||
               std::visit([](const auto& p) { return scales_moduli<dim, std::decay_t<decltype(p)>>; }, m.plasticity);
  }
  std::vector<Mat<dim>>& stress = in_cache ? *cache : weighted_stress_;
  if (in_cache)
    std::vector<Mat<dim>>().swap(weighted_stress_);
  else if (stress_free_particles_)  // the material loops below write only listed materials
    weighted_stress_.assign(P.size(), Mat<dim>::Zero());
  else
    weighted_stress_.resize(P.size());
  if (in_cache && weighted)
    stress_weight_.resize(P.size());
  else
    std::vector<double>().swap(stress_weight_);
  std::atomic<bool> finite{true};  // every stress tested where it is formed or met, in cache
  for (std::size_t m = 0; m < materials_.size(); ++m) {
    std::visit(
        [&](const auto& model, const auto& plasticity) {
          using Plasticity = std::decay_t<decltype(plasticity)>;
          const bool cached = cache && !std::is_same_v<Plasticity, plasticity::NoPlasticity>;
          tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
            // One pass: a known cached stress is taken where it is met (or tested where it is),
            // the others wait for their SVD.
            std::uint64_t non_finite = 0;  // of the stresses this range holds
            const auto needs_svd = [&](std::size_t p) {
              if (P.material[p] != m) return false;
              if (in_cache && weighted) stress_weight_[p] = P.volume0[p] * plasticity.modulus_scale(plastic[p]);
              if (!cached || !solid::known_stress((*cache)[p])) return true;
              if (!in_cache) stress[p] = weighted_kirchhoff(plasticity, P.volume0[p], (*cache)[p], plastic[p]);
              non_finite |= non_finite_bits(stress[p]);
              return false;
            };
            math::for_each_svd<dim>(
                r.begin(), r.end(), [&](std::size_t p) -> const Mat<dim>& { return F[p]; }, needs_svd,
                [&](std::size_t p, const math::Svd<dim>& f) {
                  stress[p] = in_cache ? constitutive::isotropic_kirchhoff(model, f)
                                       : weighted_kirchhoff(model, plasticity, P.volume0[p], f, plastic[p]);
                  non_finite |= non_finite_bits(stress[p]);
                });
            if (non_finite) finite.store(false, std::memory_order_relaxed);
          });
        },
        materials_[m].elastic, materials_[m].plasticity);
  }
  if (!finite.load()) check_finite(stress, name(), "particle", "Kirchhoff stress");

  // The fused scatter adds the forces to the momentum as the impulse dt f where the grid
  // update needs no velocity before the forces (all but FLIP's v_old): no force channel.
  const double impulse_dt = s.transfer.uses_old_velocity() ? 0.0 : s.dt;
  const ParticleStress<dim> S = !in_cache  ? ParticleStress<dim>(&weighted_stress_)
                                : weighted ? ParticleStress<dim>(stress, stress_weight_)
                                           : ParticleStress<dim>(stress, P.volume0);
  if (s.adaptive) {
    if (fused())
      adaptive::particles_to_grid(P, s.transfer, *s.adaptive, S, impulse_dt);
    else
      adaptive::stress_to_grid_forces(weighted_stress_, P, *s.adaptive);
  } else if (fused()) {
    particles_to_grid(P, s.buckets, s.kernel, s.transfer, s.grid, S, impulse_dt);
  } else {
    stress_to_grid_forces(weighted_stress_, P, s.buckets, s.kernel, s.grid);
  }
}

template class StressForces<2>;
template class StressForces<3>;

}  // namespace mpm::stages
