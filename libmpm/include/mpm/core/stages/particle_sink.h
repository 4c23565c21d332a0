#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mpm::stages {

//! The half-open axis-aligned region lo <= x < hi [m]; bounds may be infinite.
template <int dim>
struct SinkRegion {
  Vec<dim> lo, hi;
  bool contains(const Vec<dim>& x) const { return (x.array() >= lo.array()).all() && (x.array() < hi.array()).all(); }
};

//! The layer of depth `depth` [m] inside the face (axis, side) of the box [lo, hi] and all
//! space beyond that face: with depth = wall_layer(kernel, dx) a particle is removed before its
//! stencil can leave a grid sized to the box.
template <int dim>
SinkRegion<dim> face_region(const Vec<dim>& lo, const Vec<dim>& hi, int axis, geometry::Side side, double depth);

//! An outflow: removes every particle inside one of its regions (stable compaction,
//! Particles::erase_flagged) and records the mass and count removed, so a scene can report
//! mass in = out + stored. Precondition: a sort stage follows (the buckets are cleared when
//! particles are removed). Particles with a non-finite position are left for the sort to report.
template <int dim>
class ParticleSink final : public Stage<MpmState<dim>> {
public:
  explicit ParticleSink(std::vector<SinkRegion<dim>> regions) : regions_(std::move(regions)) {}

  std::string name() const override { return "sink"; }
  std::vector<std::string> reads() const override { return {"particle.x", "particle.mass"}; }
  std::vector<std::string> writes() const override {
    return {"particle.x", "particle.v", "particle.C", "particle.mass", "particle.volume0", "particle.material"};
  }
  void run(MpmState<dim>& s) override;
  //! The totals removed, so that a restarted run keeps counting from the checkpoint.
  CarriedData carried() const override { return {{"removed", {removed_mass_, static_cast<double>(removed_count_)}}}; }
  void restore(const CarriedData& data) override {
    for (const auto& [name, values] : data)
      if (name == "removed" && values.size() == 2) {
        removed_mass_ = values[0];
        removed_count_ = static_cast<std::size_t>(values[1]);
      }
  }

  //! Mass removed since the start of the run [kg] (a restarted run included).
  double removed_mass() const { return removed_mass_; }
  //! outflow_mass: the mass removed since the start [kg].
  std::vector<Diagnostic> diagnostics() const override { return {{"outflow_mass", removed_mass_, true}}; }
  std::size_t removed_count() const { return removed_count_; }
  const std::vector<SinkRegion<dim>>& regions() const { return regions_; }

private:
  std::vector<SinkRegion<dim>> regions_;
  std::vector<std::uint8_t> flagged_;
  double removed_mass_ = 0.0;
  std::size_t removed_count_ = 0;
};

}  // namespace mpm::stages
