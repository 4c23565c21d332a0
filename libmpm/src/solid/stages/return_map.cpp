// Return mapping in principal (SVD) space (paper sec. 4.2): F^E_trial = U Sigma V^T,
// project log(Sigma) onto the Drucker-Prager cone (Klar et al. 2016, with the volume
// correction of Tampubolon et al. 2017, and dilatancy where the material has it) or the von Mises cylinder (paper sec. 4.2.2),
// F^E = U exp(H) V^T. Elastic materials are skipped; the model is chosen outside the loop. In 3D
// the trial SVDs are taken four at a time (math::for_each_svd). A particle stage: the solvers'
// g2p calls the map on each bucket right after its gather (core/stages/particle_stage.h).
// Where the particles carry a stress cache (solid_channels.h), the Kirchhoff stress of the
// F^E left is computed from the same SVD, U diag(p_i sigma_i) U^T, for the next step's forces.
#include <mpm/core/finite_guard.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/return_map.h>

#include <utility>

namespace mpm::stages {

template <int dim>
bool any_plastic(const std::vector<Material<dim>>& materials) {
  for (const auto& m : materials)
    if (!std::holds_alternative<plasticity::NoPlasticity>(m.plasticity)) return true;
  return false;
}

template <int dim>
bool any_dilatant(const std::vector<Material<dim>>& materials) {
  for (const auto& m : materials)
    if (const auto* sand = std::get_if<plasticity::DruckerPrager<dim>>(&m.plasticity); sand && sand->dilatant())
      return true;
  return false;
}

namespace {
//! The maps in Hencky strain, which leave the log of the singular values they return.
template <int dim, class Model>
constexpr bool maps_log_strain =
    std::is_same_v<Model, plasticity::DruckerPrager<dim>> || std::is_same_v<Model, plasticity::VonMises<dim>>;

//! One particle's return map from `trial`, the SVD of F: a dilatant Drucker-Prager material
//! reads and updates the rest packing (a particle of unknown packing starts at the critical
//! one), and the step dt reaches a rate-dependent one (the others do not read it); every other
//! model has its plain map. The Hencky-strain maps also fill `log_sigma`.
template <int dim, class Model>
void project(const Model& model, Mat<dim>& F, const math::Svd<dim>& trial, double& plastic, double* packing, double dt,
             math::Svd<dim>* result, Vec<dim>* log_sigma) {
  if constexpr (std::is_same_v<Model, plasticity::DruckerPrager<dim>>) {
    if (!model.dilatant()) packing = nullptr;
    if (packing && std::isnan(*packing)) *packing = model.flow().critical_packing * F.determinant();
    model.project(F, trial, plastic, packing, dt, result, log_sigma);
  } else if constexpr (std::is_same_v<Model, plasticity::VonMises<dim>>) {
    model.project(F, trial, plastic, result, log_sigma);
  } else {
    model.project(F, trial, plastic, result);
  }
}

//! The Kirchhoff stress of the F^E a map left (SVD f): Hencky elasticity after a Hencky-strain
//! map takes the map's log strain (no logarithms again), every other pair the SVD alone.
template <int dim, class Elastic, class Model>
Mat<dim> kirchhoff_after_map(const Elastic& elastic, const math::Svd<dim>& f, const Vec<dim>& log_sigma) {
  if constexpr (std::is_same_v<Elastic, constitutive::HenckyStVK<dim>> && maps_log_strain<dim, Model>)
    return elastic.kirchhoff(f, log_sigma);
  else
    return constitutive::isotropic_kirchhoff(elastic, f);
}
}  // namespace

template <int dim>
ParticleGroupUpdate ReturnMap<dim>::bind(MpmState<dim>& s) {
  Particles<dim>& P = s.particles;
  std::vector<Mat<dim>>& F = solid::elastic_F(P);
  std::vector<double>& plastic = solid::plastic_state(P);
  std::vector<Mat<dim>>* cache = solid::stress_cache(P);
  std::vector<double>* packing = solid::rest_packing(P);
  const double dt = s.dt;
  finite_.store(true);
  return [this, &P, &F, &plastic, cache, packing, dt](const std::uint32_t* first, const std::uint32_t* last) {
    const std::size_t n = static_cast<std::size_t>(last - first);
    for (std::size_t m = 0; m < materials_.size(); ++m) {
      std::visit(
          [&](const auto& elastic, const auto& model) {
            using Model = std::decay_t<decltype(model)>;
            if constexpr (!std::is_same_v<Model, plasticity::NoPlasticity>) {
              math::Svd<dim> f;
              Vec<dim> log_sigma;
              math::for_each_svd<dim>(
                  0, n, [&](std::size_t i) -> const Mat<dim>& { return F[first[i]]; },
                  [&](std::size_t i) { return P.material[first[i]] == m; },
                  [&](std::size_t i, const math::Svd<dim>& trial) {
                    const std::uint32_t p = first[i];
                    project(model, F[p], trial, plastic[p], packing ? &(*packing)[p] : nullptr, dt,
                            cache ? &f : nullptr, cache ? &log_sigma : nullptr);
                    if (cache)
                      (*cache)[p] =
                          kirchhoff_after_map<dim, std::decay_t<decltype(elastic)>, Model>(elastic, f, log_sigma);
                  });
            }
          },
          materials_[m].elastic, materials_[m].plasticity);
    }
    // F^E tested while in cache; finish() names a particle only when a group found a bad one.
    if (!all_finite_at(F, first, last)) finite_.store(false, std::memory_order_relaxed);
  };
}

template <int dim>
void ReturnMap<dim>::finish(MpmState<dim>& s) {
  if (!finite_.load())
    check_finite(solid::elastic_F(std::as_const(s.particles)), name(), "particle", "elastic deformation gradient F^E");
}

template bool any_plastic(const std::vector<Material<2>>&);
template bool any_plastic(const std::vector<Material<3>>&);
template bool any_dilatant(const std::vector<Material<2>>&);
template bool any_dilatant(const std::vector<Material<3>>&);
template class ReturnMap<2>;
template class ReturnMap<3>;

}  // namespace mpm::stages
