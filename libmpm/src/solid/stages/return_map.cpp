// Return mapping in principal (SVD) space (paper sec. 4.2): F^E_trial = U Sigma V^T,
// project log(Sigma) onto the Drucker-Prager cone (Klar et al. 2016, with the volume
// correction of Tampubolon et al. 2017) or the von Mises cylinder (paper sec. 4.2.2),
// F^E = U exp(H) V^T. Elastic materials are skipped; the model is chosen outside the loop.
// Where the particles carry a stress cache (solid_channels.h), the Kirchhoff stress of the
// F^E left is computed from the same SVD, U diag(p_i sigma_i) U^T, for the next step's forces.
#include <mpm/core/finite_guard.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/return_map.h>

#include <tbb/parallel_for.h>

namespace mpm::stages {

template <int dim>
bool any_plastic(const std::vector<Material<dim>>& materials) {
  for (const auto& m : materials)
    if (!std::holds_alternative<plasticity::NoPlasticity>(m.plasticity)) return true;
  return false;
}

template <int dim>
void ReturnMap<dim>::run(MpmState<dim>& s) {
  Particles<dim>& P = s.particles;
  std::vector<Mat<dim>>& F = solid::elastic_F(P);
  std::vector<double>& plastic = solid::plastic_state(P);
  std::vector<Mat<dim>>* cache = solid::stress_cache(P);
  for (std::size_t m = 0; m < materials_.size(); ++m) {
    std::visit(
        [&](const auto& elastic, const auto& model) {
          using Model = std::decay_t<decltype(model)>;
          if constexpr (!std::is_same_v<Model, plasticity::NoPlasticity>) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
              math::Svd<dim> f;
              for (std::size_t p = r.begin(); p != r.end(); ++p) {
                if (P.material[p] != m) continue;
                model.project(F[p], plastic[p], cache ? &f : nullptr);
                if (cache) (*cache)[p] = constitutive::isotropic_kirchhoff(elastic, f);
              }
            });
          }
        },
        materials_[m].elastic, materials_[m].plasticity);
  }
  check_finite(F, name(), "particle", "elastic deformation gradient F^E");
}

template bool any_plastic(const std::vector<Material<2>>&);
template bool any_plastic(const std::vector<Material<3>>&);
template class ReturnMap<2>;
template class ReturnMap<3>;

}  // namespace mpm::stages
