#pragma once
//! Runs a single-phase stage (Stage<MpmState<dim>>) of libmpm or libfluid on one phase of the
//! coupled state, so the coupled pipeline reuses the phase stages unchanged. Field names are
//! prefixed with the phase ("fluid.grid.velocity") so the pipeline checks each phase apart.
#include <coupling/coupled_state.h>
#include <mpm/core/stage.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace coupling::stages {

enum class Phase { fluid, sediment };

inline std::string phase_name(Phase phase) { return phase == Phase::fluid ? "fluid" : "sediment"; }

template <int dim>
mpm::MpmState<dim>& phase_state(CoupledState<dim>& s, Phase phase) {
  return phase == Phase::fluid ? s.fluid : s.sediment;
}

template <int dim>
class OnPhase final : public mpm::Stage<CoupledState<dim>> {
public:
  OnPhase(Phase phase, std::unique_ptr<mpm::Stage<mpm::MpmState<dim>>> stage)
      : phase_(phase), stage_(std::move(stage)) {}

  std::string name() const override { return phase_name(phase_) + "." + stage_->name(); }
  std::vector<std::string> reads() const override { return prefixed(stage_->reads()); }
  std::vector<std::string> writes() const override { return prefixed(stage_->writes()); }
  void run(CoupledState<dim>& s) override { stage_->run(phase_state(s, phase_)); }
  mpm::CarriedData carried() const override { return stage_->carried(); }
  void restore(const mpm::CarriedData& data) override { stage_->restore(data); }
  void synchronize(CoupledState<dim>& s) override { stage_->synchronize(phase_state(s, phase_)); }
  //! The stage's columns; a per-phase quantity gets the phase appended ("inflow_mass_fluid").
  std::vector<mpm::Diagnostic> diagnostics() const override {
    std::vector<mpm::Diagnostic> all = stage_->diagnostics();
    for (mpm::Diagnostic& d : all)
      if (d.per_phase) {
        d.name += "_" + phase_name(phase_);
        d.per_phase = false;
      }
    return all;
  }

  Phase phase() const { return phase_; }
  mpm::Stage<mpm::MpmState<dim>>& stage() { return *stage_; }

private:
  std::vector<std::string> prefixed(std::vector<std::string> fields) const {
    for (std::string& f : fields) f = phase_name(phase_) + "." + f;
    return fields;
  }

  Phase phase_;
  std::unique_ptr<mpm::Stage<mpm::MpmState<dim>>> stage_;
};

}  // namespace coupling::stages
