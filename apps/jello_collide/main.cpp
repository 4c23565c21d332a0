// jello_collide: two elastic blocks fly at each other, collide and rebound (no gravity).
//
//   jello_collide data/scenes/jello_collide.yaml
//   jello_collide data/scenes/jello_collide_3d.yaml --set materials.0.elasticity=neo_hookean
//
// Everything comes from the generic scene keys (materials, bodies, walls). summary.json:
// momentum_drift (|P(end) - P(0)| / sum m|v(0)|: grid forces are internal, so APIC keeps the
// total momentum to round-off while the blocks touch no wall), kinetic_energy_ratio
// (KE(end) / KE(0)), energy_ratio ((KE + elastic energy)(end) over the same at the start: 1 less
// the share the transfers dissipated), rebound (1 when every body's mean velocity reversed its x
// sign) and, with two materials or more, min_body_gap: the closest the first two materials'
// bodies came, over every step, each particle a ball deformed by F^E (geometry/body_gap.h; also
// a diagnostics column). --check asserts momentum_drift < 1e-9 and rebound.
#include <mpm/core/app.h>
#include <mpm/core/runner.h>
#include <mpm/geometry/body_gap.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

using namespace mpm;

namespace {

template <int dim>
struct Totals {
  Vec<dim> momentum = Vec<dim>::Zero();
  double momentum_scale = 0.0, kinetic = 0.0;
  std::map<int, double> mean_vx;  // per material (each block its own material)

  explicit Totals(const Particles<dim>& P) {
    std::map<int, double> mass;
    for (std::size_t p = 0; p < P.size(); ++p) {
      momentum += P.mass[p] * P.v[p];
      momentum_scale += P.mass[p] * P.v[p].norm();
      kinetic += 0.5 * P.mass[p] * P.v[p].squaredNorm();
      mean_vx[P.material[p]] += P.mass[p] * P.v[p][0];
      mass[P.material[p]] += P.mass[p];
    }
    for (auto& [m, v] : mean_vx) v /= mass[m];
  }
};

//! The smallest gap between materials 0 and 1 over the steps so far, the particles' balls
//! deformed by F^E, up to `reach` (4 widths of the largest particle): past that the bodies are not
//! in contact. Carried for restarts.
template <int dim>
class MeasureBodyGap : public Stage<MpmState<dim>> {
public:
  explicit MeasureBodyGap(double reach) : reach_(reach), min_gap_(reach) {}
  std::string name() const override { return "body_gap"; }
  std::vector<std::string> reads() const override {
    return {"particle.x", "particle.volume0", "particle.material", "particle.F"};
  }
  std::vector<std::string> writes() const override { return {}; }
  // Only pairs closer than the smallest gap so far can lower it, so the search shrinks with it
  // (any positive search finds the pairs of a negative gap: their balls overlap).
  void run(MpmState<dim>& s) override {
    const double search = std::max(min_gap_, 1e-6 * reach_);
    min_gap_ = std::min(min_gap_, geometry::body_gap(s.particles, 0, 1, search, &solid::elastic_F(s.particles)));
  }
  CarriedData carried() const override { return {{"min_body_gap", {min_gap_}}}; }
  void restore(const CarriedData& data) override {
    for (const auto& [name, values] : data)
      if (name == "min_body_gap" && values.size() == 1) min_gap_ = values[0];
  }
  std::vector<Diagnostic> diagnostics() const override { return {{"min_body_gap", min_gap_}}; }
  double min_gap() const { return min_gap_; }

private:
  double reach_, min_gap_;
};

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  solid::SolidScene<dim> solid = solid::load_solid_scene<dim>(scene);
  if (solid.state.particles.size() == 0) scene.fail("bodies", "the scene needs bodies to collide");
  scene.reject_unknown_keys();

  const Totals<dim> before(solid.state.particles);
  auto elastic_energy = [&](const MpmState<dim>& s) { return solid::elastic_energy(s, solid.materials); };
  const double energy_before = before.kinetic + elastic_energy(solid.state);
  auto pipeline = solid::make_solid_pipeline(solid);
  MeasureBodyGap<dim>* gap = nullptr;
  if (solid.materials.size() >= 2 && solid.state.particles.size() > 0) {
    const auto& V = solid.state.particles.volume0;
    const double width = std::pow(*std::max_element(V.begin(), V.end()), 1.0 / dim);
    auto stage = std::make_unique<MeasureBodyGap<dim>>(4.0 * width);
    gap = stage.get();
    pipeline.add(std::move(stage));
  }
  Runner<dim> runner("jello_collide", cl, scene, solid.settings);
  runner.set_elastic_energy(elastic_energy);
  runner.run(solid.state, pipeline);
  const Totals<dim> after(solid.state.particles);

  const double drift = (after.momentum - before.momentum).norm() / before.momentum_scale;
  bool rebound = before.mean_vx.size() >= 2;
  for (const auto& [m, v] : before.mean_vx) rebound = rebound && v * after.mean_vx.at(m) < 0.0;
  std::vector<std::pair<std::string, double>> results{
      {"momentum_drift", drift},
      {"kinetic_energy_ratio", after.kinetic / before.kinetic},
      {"energy_ratio", (after.kinetic + elastic_energy(solid.state)) / energy_before},
      {"rebound", rebound ? 1.0 : 0.0}};
  if (gap) results.emplace_back("min_body_gap", gap->min_gap());
  runner.write_summary(results);
  if (cl.check) {
    const bool ok = check_value("momentum_drift", drift, 0.0, 1e-9);
    return ok && check_value("rebound", rebound, 1.0, 0.0) ? 0 : 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "jello_collide", "Two elastic blocks collide", run<2>, run<3>);
}
