#pragma once
//! Height of a sediment bed per column, for the scenes that measure scour, deposition and
//! piles (sediment_transport, sand_pour). Columns are dx wide along every axis but the
//! vertical y (axis 1): along x in 2D, over (x, z) in 3D. The height of a column is the grain
//! volume it holds per unit area over the packing fraction phi of a settled bed,
//! h = sum_p V_p / (dx^(dim-1) phi), so grains in suspension above the bed count only as the
//! thin layer they would settle into.
#include <mpm/core/particles.h>
#include <mpm/core/scene_settings.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace coupling {

template <int dim>
class BedProfile {
public:
  //! Columns over the domain of `settings`; `packing` phi in (0, 1).
  BedProfile(const mpm::SceneSettings<dim>& settings, double packing);

  //! h per column [m] (column index: x fastest, then z) of the grains (volume0 = grain volume).
  std::vector<double> heights(const mpm::Particles<dim>& grains) const;
  //! Column holding x, -1 outside the domain.
  std::int64_t column(const mpm::Vec<dim>& x) const;
  //! Centre of column c (y = 0) [m].
  mpm::Vec<dim> centre(std::int64_t c) const;
  std::int64_t column_count() const;

  //! (largest drop h0 - h, largest rise h - h0), both >= 0 [m], over the columns whose centres
  //! lie in [lo, hi] (y ignored).
  std::pair<double, double> change(const std::vector<double>& h0, const std::vector<double>& h, const mpm::Vec<dim>& lo,
                                   const mpm::Vec<dim>& hi) const;

private:
  mpm::Vec<dim> lo_;
  double dx_, packing_;
  mpm::IVec<dim> counts_;
};

}  // namespace coupling
