// Continuum <-> discrete switching (coupling/stages/reclassify_sediment.h), after G2P:
//   n_s,i  = the coupled step's fraction (wet) or m_s,i / (rho_s dx^dim) (dry),
//   phi_p  = sum_i w_ip n_s,i at the advected x_p (one step behind the fractions, like every
//            explicit estimate of the step),
//   continuum -> discrete if phi_p < phi_low (and, with a bed-load closure, the particle's
//   column's wall stress reaches the suspending stress), discrete -> continuum if phi_p > phi_high,
//   F^E = I and plastic = 0 for every particle that is discrete now or was during the step
//   (g2p moved its F; a new continuum particle starts stress-free), and a
//   dilatant sand's rest packing unknown (the return map starts it at the critical packing).
// The stencil reads the nodes through node_index: after advection a particle may leave the
// patch of the bucket it was sorted into, and nodes that are not allocated hold no sediment.
#include <coupling/stages/reclassify_sediment.h>
#include <mpm/core/error.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/solid/solid_channels.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <variant>

namespace coupling {

template <int dim>
SedimentCounts count_sediment(const CoupledState<dim>& s) {
  SedimentCounts n;
  if (!s.has_sediment) return n;
  for (std::uint16_t m : s.sediment.particles.material) ++(m == discrete_grain ? n.discrete : n.continuum);
  return n;
}

namespace stages {

template <int dim>
ReclassifySediment<dim>::ReclassifySediment(SedimentSwitching thresholds, double sediment_density,
                                            std::uint16_t continuum, bool wet, std::optional<double> suspending_stress)
    : thresholds_(thresholds),
      rho_s_(sediment_density),
      continuum_(continuum),
      wet_(wet),
      suspending_stress_(suspending_stress) {
  mpm::verify<mpm::InputError>(
      thresholds.dilute_below > 0.0 && thresholds.dilute_below < thresholds.dense_above && thresholds.dense_above < 1.0,
      "sediment switching: expected 0 < dilute_below < dense_above < 1 (got " +
          std::to_string(thresholds.dilute_below) + ", " + std::to_string(thresholds.dense_above) + ")");
  mpm::verify<mpm::InputError>(continuum != discrete_grain, "sediment switching: no continuum material");
  mpm::verify<mpm::InputError>(!suspending_stress || *suspending_stress > 0.0,
                               "sediment switching: expected a suspending wall stress > 0 (got " +
                                   std::to_string(suspending_stress.value_or(0.0)) + " Pa)");
}

template <int dim>
std::vector<std::string> ReclassifySediment<dim>::reads() const {
  std::vector<std::string> r{"sediment.particle.x", "sediment.particle.material",
                             wet_ ? "fractions" : "sediment.grid.mass"};
  if (suspending_stress_) r.push_back("bed");
  return r;
}

template <int dim>
std::vector<mpm::Diagnostic> ReclassifySediment<dim>::diagnostics() const {
  if (!suspending_stress_) return {};
  return {{"grains_held_as_bed_load", double(held_)}};
}

template <int dim>
void ReclassifySediment<dim>::run(CoupledState<dim>& s) {
  mpm::Particles<dim>& P = s.sediment.particles;
  const mpm::SparseGrid<dim>& g = s.sediment.grid;
  const std::vector<double>* n_s = &s.fractions.sediment;
  if (!wet_) {
    const double scale = 1.0 / (rho_s_ * std::pow(g.dx(), dim));
    dry_fraction_.resize(g.node_storage());
    for (std::size_t k = 0; k < dry_fraction_.size(); ++k) dry_fraction_[k] = g.mass[k] * scale;
    n_s = &dry_fraction_;
  }
  mpm::verify<mpm::NumericalError>(n_s->size() == g.node_storage(),
                                   "stage 'reclassify': node fractions do not match the sediment grid");

  phi_p_.resize(P.size());
  const mpm::CellMap<dim> cells(g);
  std::visit(
      [&](const auto& kernel) {
        constexpr int S = std::decay_t<decltype(kernel)>::support;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
          for (std::size_t p = r.begin(); p != r.end(); ++p) {
            const mpm::Vec<dim> xi = cells(P.x[p]);
            int base[dim];
            double w[dim][S], dw[S];
            for (int a = 0; a < dim; ++a) kernel(xi[a], base[a], w[a], dw);
            double phi = 0.0;
            for (int n = 0; n < mpm::ipow(S, dim); ++n) {
              mpm::IVec<dim> node;
              double weight = 1.0;
              for (int a = 0, rest = n; a < dim; ++a, rest /= S) {
                node[a] = base[a] + rest % S;
                weight *= w[a][rest % S];
              }
              if (const mpm::Index i = g.node_index(node); i >= 0) phi += weight * (*n_s)[static_cast<std::size_t>(i)];
            }
            phi_p_[p] = phi;
          }
        });
      },
      s.sediment.kernel);

  // With a bed-load closure: whether the current of the particle's column can suspend it (a
  // step without a layer has no current over any bed).
  const auto suspended = [&](std::size_t p) {
    if (!suspending_stress_) return true;
    const std::int64_t col = bed_column(g, s.bed.up, P.x[p]);
    return col >= 0 && std::size_t(col) < s.bed.stress.size() &&
           s.bed.stress[std::size_t(col)].norm() >= *suspending_stress_;
  };
  to_discrete_ = to_continuum_ = held_ = 0;
  std::vector<mpm::Mat<dim>>& F = mpm::solid::elastic_F(P);
  std::vector<double>& plastic = mpm::solid::plastic_state(P);
  std::vector<mpm::Mat<dim>>* cache = mpm::solid::stress_cache(P);
  std::vector<double>* packing = mpm::solid::rest_packing(P);
  for (std::size_t p = 0; p < P.size(); ++p) {
    const bool was_discrete = P.material[p] == discrete_grain;
    if (was_discrete && phi_p_[p] > thresholds_.dense_above) {
      P.material[p] = continuum_;
      ++to_continuum_;
    } else if (!was_discrete && phi_p_[p] < thresholds_.dilute_below) {
      if (suspended(p)) {
        P.material[p] = discrete_grain;
        ++to_discrete_;
      } else {
        ++held_;
      }
    }
    if (was_discrete || P.material[p] == discrete_grain) {
      F[p] = mpm::Mat<dim>::Identity();
      plastic[p] = 0.0;
      if (cache) (*cache)[p].setZero();  // tau(I) = 0
      // The kernel estimate is biased at free surfaces: a joining grain starts critical.
      if (packing) (*packing)[p] = std::numeric_limits<double>::quiet_NaN();
    }
  }
}

template class ReclassifySediment<2>;
template class ReclassifySediment<3>;

}  // namespace stages

template SedimentCounts count_sediment(const CoupledState<2>&);
template SedimentCounts count_sediment(const CoupledState<3>&);

}  // namespace coupling
