#include <coupling/pressure_probe.h>

#include <coupling/stages/mixture_projection.h>
#include <fluid/solver/weakly_compressible_solver.h>
#include <fluid/stages/equation_of_state.h>

#include <cmath>
#include <limits>

namespace coupling {

template <int dim>
PressureProbe<dim> liquid_pressure_probe(const CoupledScene<dim>& scene, mpm::Pipeline<CoupledState<dim>>& pipeline) {
  if (!scene.fluid_solver) return {};
  if (const auto* mixture = pipeline.template find<stages::MixtureProjection<dim>>())
    return [mixture](const CoupledState<dim>& s, const mpm::Vec<dim>& x) {
      return mixture->projection().pressure_at(s.fluid.grid, x);
    };
  if (const auto* liquid = dynamic_cast<const fluid::WeaklyCompressibleSolver<dim>*>(scene.fluid_solver.get()))
    return [eos = liquid->equation_of_state()](const CoupledState<dim>& s, const mpm::Vec<dim>& x) {
      const mpm::Particles<dim>& P = s.fluid.particles;
      const std::vector<double>& own = fluid::own_volume_ratio(P);
      const double half = 0.5 * s.fluid.grid.dx();
      double sum = 0.0;
      int count = 0;
      for (std::size_t p = 0; p < P.size(); ++p)
        if (((P.x[p] - x).array().abs() <= half).all()) {
          sum += eos.pressure(own[p]);
          ++count;
        }
      return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
    };
  return {};
}

template PressureProbe<2> liquid_pressure_probe(const CoupledScene<2>&, mpm::Pipeline<CoupledState<2>>&);
template PressureProbe<3> liquid_pressure_probe(const CoupledScene<3>&, mpm::Pipeline<CoupledState<3>>&);

}  // namespace coupling
