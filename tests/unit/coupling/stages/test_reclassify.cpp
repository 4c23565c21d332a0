// Continuum <-> discrete switching of sediment particles (coupling/stages/reclassify_sediment.h):
// phi_p reproduces a uniform fraction to round-off; hysteresis keeps the state between the
// thresholds and switches across them; a switched particle starts with F = I; in the coupled
// pipeline a dense bed stays continuum and an isolated grain turns discrete; a bed deposited
// as discrete grains, dry or under water, does not expand when it turns continuum (the same
// bed keeping its old F^E would); with a bed-load closure only the grains of columns whose
// current can suspend them turn discrete.
#include <coupling/scene_loader.h>
#include <coupling/stages/on_phase.h>
#include <coupling/stages/reclassify_sediment.h>
#include <doctest/doctest.h>
#include <mpm/core/advance.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/geometry/seeding.h>
#include <mpm/solid/solid_channels.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace coupling;
using mpm::Mat;
using mpm::Vec;

namespace {

constexpr double kRhoS = 2650.0;
constexpr char kSand[] =
    "{density: 2650, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk, "
    "plasticity: {model: drucker_prager, friction_angle: 30}}";

struct Block {
  CoupledScene<2> scene;
  std::vector<bool> interior;  // three cells or more inside the block: phi_p sees phi exactly
};

//! A dry block of 12 x 12 cells, 4 particles per cell at grain fraction phi, every particle of
//! material `material` with F = F0 and plastic state `plastic0`; sorted and rasterised.
Block block(double phi, std::uint16_t material, const Mat<2>& F0, double plastic0) {
  const mpm::Config cfg = mpm::Config::parse(std::string(R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.0625}
time: {end: 1}
gravity: [0, 0]
sediment: )") + kSand);
  SedimentPhase<2> sand = parse_sediment_phase<2>(cfg.child("sediment"));
  mpm::SceneSettings<2> settings = mpm::parse_scene_settings<2>(cfg);
  Block b{make_coupled_scene<2>(settings, {}, std::nullopt, {}, sand, std::nullopt), {}};
  const double dx = settings.dx, lo = 0.125, hi = 0.875;
  const auto x = mpm::geometry::seed_box<2>(Vec<2>::Constant(lo), Vec<2>::Constant(hi), dx, 4, 0.0, 1);
  add_sediment_particles<2>(b.scene, x, phi * mpm::geometry::particle_volume<2>(dx, 4), Vec<2>::Zero(), "block");
  mpm::Particles<2>& P = b.scene.state.sediment.particles;
  std::vector<Mat<2>>& F = mpm::solid::elastic_F(P);
  std::vector<double>& plastic = mpm::solid::plastic_state(P);
  for (std::size_t p = 0; p < P.size(); ++p) {
    P.material[p] = material;
    F[p] = F0;
    plastic[p] = plastic0;
    b.interior.push_back((P.x[p].array() > lo + 3 * dx).all() && (P.x[p].array() < hi - 3 * dx).all());
  }
  using stages::OnPhase;
  OnPhase<2>(stages::Phase::sediment, std::make_unique<mpm::stages::SortParticles<2>>()).run(b.scene.state);
  OnPhase<2>(stages::Phase::sediment, std::make_unique<mpm::stages::ParticlesToGrid<2>>()).run(b.scene.state);
  return b;
}

//! A scene file: a bed wall to wall (36 x 8 cells at phi = 0.6) and `extra` bodies; `wet`: under
//! 0.075 m of water that fills its pores.
mpm::Config bed_scene(const std::string& switching, const std::string& extra = "", bool wet = false) {
  const std::string sand(kSand);
  return mpm::Config::parse(std::string(R"(
dim: 2
domain: {lo: [0, 0], hi: [0.5, 0.25]}
grid: {dx: 0.0125}
time: {end: 0.3}
gravity: [0, -9.81]
walls: {contact: )") + (wet ? "sticky" : "slip") +
                            "}\nsediment: " + sand.substr(0, sand.size() - 1) + switching + "}\n" +
                            (wet ? "fluid: {density: 1000, viscosity: 1.0e-3}\n"
                                   "drag: {law: di_felice, grain_diameter: 5.0e-4}\n"
                                   "pressure: {solver: mgpcg, tolerance: 1.0e-10}\n"
                                 : "") +
                            R"(bodies:
  - {phase: sediment, shape: box, lo: [0.025, 0.025], hi: [0.475, 0.125], packing_fraction: 0.6}
)" + (wet ? "  - {phase: fluid, shape: box, lo: [0.025, 0.025], hi: [0.475, 0.2]}\n" : "") +
                            extra);
}

double top(const CoupledState<2>& s) {
  double y = -1e300;
  for (const Vec<2>& x : s.sediment.particles.x) y = std::max(y, x[1]);
  return y;
}

double grain_volume(const CoupledState<2>& s) {
  double V = 0.0;
  for (double m : s.sediment.particles.mass) V += m / kRhoS;
  return V;
}

}  // namespace

TEST_CASE("reclassify: phi_p of a uniform block, hysteresis, stress-free start") {
  const SedimentSwitching band;  // 0.2, 0.45
  const Mat<2> squeezed = 0.9 * Mat<2>::Identity();
  struct Case {
    double phi;
    std::uint16_t before, after;
  };
  // Between the thresholds both states persist; above phi_high discrete grains join the
  // continuum; below phi_low continuum particles turn discrete.
  for (const Case& c : {Case{0.3, 0, 0}, Case{0.3, discrete_grain, discrete_grain}, Case{0.5, discrete_grain, 0},
                        Case{0.5, 0, 0}, Case{0.1, 0, discrete_grain}, Case{0.1, discrete_grain, discrete_grain}}) {
    CAPTURE(c.phi);
    CAPTURE(c.before);
    Block b = block(c.phi, c.before, squeezed, 0.2);
    stages::ReclassifySediment<2> reclassify(band, kRhoS, 0, false);
    reclassify.run(b.scene.state);
    const mpm::Particles<2>& P = b.scene.state.sediment.particles;
    const std::vector<Mat<2>>& F = mpm::solid::elastic_F(P);
    const std::vector<double>& plastic = mpm::solid::plastic_state(P);
    int checked = 0;
    for (std::size_t p = 0; p < P.size(); ++p) {
      if (!b.interior[p]) continue;
      ++checked;
      REQUIRE(reclassify.particle_fraction()[p] == doctest::Approx(c.phi).epsilon(1e-12));
      REQUIRE(P.material[p] == c.after);
      // A particle that is or was discrete restarts stress-free; a continuum one keeps F^E.
      const bool reset = c.before == discrete_grain || c.after == discrete_grain;
      REQUIRE((F[p] - (reset ? Mat<2>::Identity() : squeezed)).norm() == 0.0);
      REQUIRE(plastic[p] == (reset ? 0.0 : 0.2));
    }
    CHECK(checked == 6 * 6 * 4);
    const auto switched = std::count_if(P.material.begin(), P.material.end(), [&](auto m) { return m != c.before; });
    CHECK((c.before == discrete_grain ? reclassify.to_continuum() : reclassify.to_discrete()) == switched);
    CHECK((c.before == discrete_grain ? reclassify.to_discrete() : reclassify.to_continuum()) == 0);
    const SedimentCounts n = count_sediment(b.scene.state);
    CHECK(n.continuum + n.discrete == static_cast<mpm::Index>(P.size()));
  }
}

TEST_CASE("reclassify with a bed-load closure: only the grains of columns whose current suspends them") {
  // A thin block (phi = 0.1 < phi_low) under a layer whose columns left of x = 0.46875 m (the
  // nodes x <= 7 dx; a particle's column is its nearest node's) carry just the suspending stress
  // and the others just less.
  constexpr double suspending = 5.3;  // [Pa]
  Block b = block(0.1, 0, Mat<2>::Identity(), 0.0);
  CoupledState<2>& s = b.scene.state;
  s.bed.up = 1;
  const int columns = s.sediment.grid.node_counts()[0];
  s.bed.stress.assign(std::size_t(columns), Vec<2>::Zero());
  const double dx = s.sediment.grid.dx(), split = 7.5 * dx;
  for (int i = 0; i < columns; ++i)
    s.bed.stress[std::size_t(i)] = (i * dx < split ? 1.0 : 1.0 - 1e-12) * suspending * Vec<2>(0.6, 0.8);
  stages::ReclassifySediment<2> reclassify(SedimentSwitching{}, kRhoS, 0, false, suspending);
  reclassify.run(s);
  const mpm::Particles<2>& P = s.sediment.particles;
  mpm::Index left = 0, dilute = 0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    if (!b.interior[p]) continue;
    REQUIRE(reclassify.particle_fraction()[p] < SedimentSwitching{}.dilute_below);
    CHECK(P.material[p] == (P.x[p][0] < split ? discrete_grain : std::uint16_t{0}));
  }
  for (std::size_t p = 0; p < P.size(); ++p) {
    left += P.x[p][0] < split;
    dilute += reclassify.particle_fraction()[p] < SedimentSwitching{}.dilute_below;
  }
  CHECK(left > 0);
  CHECK(reclassify.to_discrete() == left);
  CHECK(reclassify.to_discrete() + reclassify.held_as_bed_load() == dilute);
  CHECK(reclassify.held_as_bed_load() > 0);
  // A step without a layer has no current: every grain stays in the continuum.
  Block calm = block(0.1, 0, Mat<2>::Identity(), 0.0);
  stages::ReclassifySediment<2>(SedimentSwitching{}, kRhoS, 0, false, suspending).run(calm.scene.state);
  CHECK(count_sediment(calm.scene.state).discrete == 0);
}

TEST_CASE("reclassify in the dry pipeline: a dense bed stays continuum, an isolated grain turns discrete") {
  // One particle of a 4-per-cell lattice, far from the bed: its own grain volume gives
  // phi_p ~ 0.05.
  const mpm::Config cfg = bed_scene(", switching: {}", R"(
  - {phase: sediment, shape: box, lo: [0.25, 0.2], hi: [0.25625, 0.20625], packing_fraction: 0.6}
)");
  CoupledScene<2> scene = load_coupled_scene<2>(cfg);
  REQUIRE(cfg.integer("dim", 2, 2, 3) == 2);  // read by the apps' entry point
  cfg.reject_unknown_keys();
  CoupledState<2>& s = scene.state;
  const mpm::Index n = static_cast<mpm::Index>(s.sediment.particles.size());
  REQUIRE(n == 36 * 8 * 4 + 1);
  CHECK(count_sediment(s).continuum == n);
  auto pipeline = make_coupled_pipeline(scene);
  mpm::advance(s, pipeline, 0.05);
  const SedimentCounts counts = count_sediment(s);
  CHECK(counts.discrete == 1);
  CHECK(counts.continuum == n - 1);
  // The grain is the highest particle and falls freely (no stress reaches it).
  const mpm::Particles<2>& P = s.sediment.particles;
  const auto grain = std::max_element(P.x.begin(), P.x.end(), [](auto& a, auto& b) { return a[1] < b[1]; });
  CHECK(P.material[static_cast<std::size_t>(grain - P.x.begin())] == discrete_grain);
}

TEST_CASE("reclassify: a bed deposited as discrete grains does not expand when it turns continuum") {
  struct Run {
    double top0, highest;    // bed top before and the highest over the run [m]
    double grains0, grains;  // sum m_p / rho_s before and after [m^2]
    double volume;           // sum V_p^0 det F^E after: the volume the continuum's stress sees
    SedimentCounts counts;
  };
  // 300 steps of the bed, every grain of material `material` with a compressed F^E = 0.9 I,
  // as an earlier continuum life would leave it.
  auto run = [](const std::string& switching, std::uint16_t material, bool wet) {
    CoupledScene<2> scene = load_coupled_scene<2>(bed_scene(switching, "", wet));
    CoupledState<2>& s = scene.state;
    mpm::Particles<2>& P = s.sediment.particles;
    std::vector<Mat<2>>& F = mpm::solid::elastic_F(P);
    for (std::size_t p = 0; p < P.size(); ++p) {
      P.material[p] = material;
      F[p] = 0.9 * Mat<2>::Identity();
    }
    Run r{top(s), top(s), grain_volume(s), 0.0, 0.0, {}};
    auto pipeline = make_coupled_pipeline(scene);
    while (s.step < (wet ? 150 : 300)) {
      mpm::advance(s, pipeline, s.time + 1e-3);
      r.highest = std::max(r.highest, top(s));
    }
    r.grains = grain_volume(s);
    for (std::size_t p = 0; p < P.size(); ++p) r.volume += P.volume0[p] * F[p].determinant();
    r.counts = count_sediment(s);
    MESSAGE((wet ? "wet" : "dry") << ", switching '" << switching << "': top " << r.top0 << " -> highest " << r.highest
                                  << " m, " << r.counts.discrete << " of " << P.size() << " discrete, t = " << s.time
                                  << " s");
    return r;
  };
  const double dx = 0.0125;
  for (const bool wet : {false, true}) {
    CAPTURE(wet);
    const Run bed = run(", switching: {}", discrete_grain, wet);
    CHECK(bed.highest <= bed.top0 + 1e-3 * dx);
    CHECK(bed.grains == bed.grains0);
    CHECK(bed.volume <= bed.grains0);
    CHECK(bed.counts.continuum > 36 * 8 * 4 * 3 / 4);  // all but the outer particle rows
  }
  // Control: the same bed as a continuum that keeps its compressed F^E swells by ~ 10 %.
  const Run kept = run("", 0, false);
  CHECK(kept.highest > kept.top0 + 0.5 * dx);
}
