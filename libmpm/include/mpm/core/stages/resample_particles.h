#pragma once
#include <mpm/adaptive/resampling.h>
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

#include <limits>
#include <string>
#include <vector>

namespace mpm::stages {

//! Adaptive grids only: every `every` steps, or once the particles may have travelled
//! `max_travel` since the last resampling, splits the coarse particles near the free surface
//! and merges the fine ones deep inside (adaptive/resampling.h, Gao et al. 2017, sec. 7.2), at
//! the start of the step, before stage 'refine' matches the grid to the particle types.
//! `deformation` names the Mat channels merged as deformation gradients (the solid's F).
//! Precondition: a sort stage follows (the buckets are cleared when the particles change).
//!
//! The travel is bounded by sum_k dt_k max_p |v_p^(k+1)|: each step moves x_p by dt v_p with the
//! velocity the step leaves (the one this stage finds at the start of the next). An explicit
//! step is bound by the elastic wave, not by the particles (dt <= cfl dx / c with c some 30 m/s
//! for the sand scenes against particle speeds of 1-2 m/s), so the particles cross a few
//! hundredths of a cell per step and a resampling every step redoes the same split and merge.
//! The totals split and merged, the resamplings and the travel are carried, so a restarted run
//! keeps counting and resamples at the same steps.
template <int dim>
class ResampleParticles final : public Stage<MpmState<dim>> {
public:
  //! `walls`: the domain's closed walls on the finest cells, no free surface (default: none).
  ResampleParticles(adaptive::ResampleSettings settings, std::vector<std::string> deformation,
                    adaptive::LatticeWalls<dim> walls = {})
      : settings_(settings), deformation_(std::move(deformation)), walls_(walls) {}
  std::string name() const override { return "resample"; }
  std::vector<std::string> reads() const override { return {"particle.x", "particle.level"}; }
  std::vector<std::string> writes() const override {
    std::vector<std::string> w{"particle.x",    "particle.v",       "particle.C",
                               "particle.mass", "particle.volume0", "particle.level"};
    for (const std::string& name : deformation_) w.push_back("particle." + name);
    return w;
  }
  void run(MpmState<dim>& s) override;
  CarriedData carried() const override {
    return {
        {"resampled", {static_cast<double>(split_), static_cast<double>(merged_), static_cast<double>(resamplings_)}},
        {"travel", {travel_}}};
  }
  void restore(const CarriedData& data) override {
    for (const auto& [name, values] : data)
      if (name == "resampled" && values.size() >= 2) {  // two before the resamplings were counted
        split_ = static_cast<std::size_t>(values[0]);
        merged_ = static_cast<std::size_t>(values[1]);
        if (values.size() == 3) resamplings_ = static_cast<std::size_t>(values[2]);
      } else if (name == "travel" && values.size() == 1) {
        travel_ = values[0];
      }
  }
  //! particles_split, particles_merged, resamplings: the totals since the start of the run.
  std::vector<Diagnostic> diagnostics() const override {
    return {{"particles_split", static_cast<double>(split_), true},
            {"particles_merged", static_cast<double>(merged_), true},
            {"resamplings", static_cast<double>(resamplings_), true}};
  }

private:
  //! Whether this step resamples (by steps, or by the travel since the last resampling).
  bool due(const MpmState<dim>& s);

  adaptive::ResampleSettings settings_;
  std::vector<std::string> deformation_;
  adaptive::LatticeWalls<dim> walls_;
  std::size_t split_ = 0, merged_ = 0, resamplings_ = 0;
  //! The particles' largest travel since the last resampling [m]; none yet: the first step resamples.
  double travel_ = std::numeric_limits<double>::infinity();
};

}  // namespace mpm::stages
