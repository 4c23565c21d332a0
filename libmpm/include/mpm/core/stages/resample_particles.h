#pragma once
#include <mpm/adaptive/resampling.h>
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

#include <string>
#include <vector>

namespace mpm::stages {

//! Adaptive grids only: every `every` steps, splits the coarse particles near the free surface
//! and merges the fine ones deep inside (adaptive/resampling.h, Gao et al. 2017, sec. 7.2), at
//! the start of the step, before stage 'refine' matches the grid to the particle types.
//! `deformation` names the Mat channels merged as deformation gradients (the solid's F).
//! Precondition: a sort stage follows (the buckets are cleared when the particles change).
//! The totals split and merged are carried, so a restarted run keeps counting.
template <int dim>
class ResampleParticles final : public Stage<MpmState<dim>> {
public:
  ResampleParticles(adaptive::ResampleSettings settings, std::vector<std::string> deformation)
      : settings_(settings), deformation_(std::move(deformation)) {}
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
    return {{"resampled", {static_cast<double>(split_), static_cast<double>(merged_)}}};
  }
  void restore(const CarriedData& data) override {
    for (const auto& [name, values] : data)
      if (name == "resampled" && values.size() == 2) {
        split_ = static_cast<std::size_t>(values[0]);
        merged_ = static_cast<std::size_t>(values[1]);
      }
  }
  //! particles_split, particles_merged: the totals since the start of the run.
  std::vector<Diagnostic> diagnostics() const override {
    return {{"particles_split", static_cast<double>(split_), true},
            {"particles_merged", static_cast<double>(merged_), true}};
  }

private:
  adaptive::ResampleSettings settings_;
  std::vector<std::string> deformation_;
  std::size_t split_ = 0, merged_ = 0;
};

}  // namespace mpm::stages
