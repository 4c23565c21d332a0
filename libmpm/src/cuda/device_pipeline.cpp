// The host side of the CUDA back-end: which scenes the device step runs (everything else is an
// input error at the `device` key), the translation of materials and obstacles into the
// device's plain structs, the memory check, and the stage that holds the device particles and
// brings the host particles up to date at frame ends.
#include <mpm/core/stages/time_step_control.h>
#include <mpm/cuda/device_pipeline.h>
#include <mpm/solid/solid_channels.h>

#include "device_solid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace mpm::cuda {

Device parse_device(const Config& scene) {
  Device d;
  d.cuda = scene.choice("device", "cpu", {"cpu", "cuda"}) == "cuda";
  d.single_precision = scene.choice("device_precision", "double", {"double", "single"}) == "single";
  return d;
}

std::string unavailable_reason() {
  if (!built_with_cuda())
    return "this build has no CUDA back-end (configure with -DSEDIMENT_WITH_CUDA=ON on a machine where nvcc is found)";
  return detail::device_unavailable_reason();
}

namespace {

using detail::DeviceCollider;
using detail::DeviceMaterial;
using detail::DeviceScene;

//! The device's copy of a material, or "" and the reason it has none.
DeviceMaterial device_material(const Material<3>& m, std::string& refused) {
  DeviceMaterial d{};
  d.mu = m.lame.mu;
  d.lambda = m.lame.lambda;
  std::visit(
      [&](const auto& model) {
        using Model = std::decay_t<decltype(model)>;
        if constexpr (std::is_same_v<Model, constitutive::FixedCorotated<3>>)
          d.elasticity = detail::Elasticity::fixed_corotated;
        else if constexpr (std::is_same_v<Model, constitutive::NeoHookean<3>>)
          d.elasticity = detail::Elasticity::neo_hookean;
        else if constexpr (std::is_same_v<Model, constitutive::HenckyStVK<3>>)
          d.elasticity = detail::Elasticity::hencky_stvk;
        else
          refused = "elasticity " + std::string(Model::name);
      },
      m.elastic);
  std::visit(
      [&](const auto& model) {
        using Model = std::decay_t<decltype(model)>;
        if constexpr (std::is_same_v<Model, plasticity::NoPlasticity>) {
          d.plasticity = detail::Plasticity::none;
        } else if constexpr (std::is_same_v<Model, plasticity::DruckerPrager<3>>) {
          d.plasticity = detail::Plasticity::drucker_prager;
          d.alpha = model.cone_alpha();
          d.k = model.cone_k();
          if (model.dilatant() || model.rate_dependent())
            refused = "Drucker-Prager with dilatancy or rate-dependent friction";
        } else if constexpr (std::is_same_v<Model, plasticity::VonMises<3>>) {
          d.plasticity = detail::Plasticity::von_mises;
          d.yield_stress = model.yield_stress();
        } else {
          refused = "plasticity " + std::string(Model::name);
        }
      },
      m.plasticity);
  return d;
}

//! The device's copy of an obstacle, or the reason it has none.
DeviceCollider device_collider(const geometry::Collider<3>& c, std::string& refused) {
  DeviceCollider d;
  std::visit(
      [&](const auto& shape) {
        using Shape = std::decay_t<decltype(shape)>;
        if constexpr (std::is_same_v<Shape, geometry::HalfSpace<3>>) {
          d.shape = DeviceCollider::half_space;
          const Vec<3> n = shape.normal(shape.point());
          for (int a = 0; a < 3; ++a) d.a[a] = shape.point()[a], d.b[a] = n[a];
        } else if constexpr (std::is_same_v<Shape, geometry::Box<3>>) {
          d.shape = DeviceCollider::box;
          for (int a = 0; a < 3; ++a) d.a[a] = shape.center()[a], d.b[a] = shape.half_size()[a];
        } else if constexpr (std::is_same_v<Shape, geometry::Sphere<3>>) {
          d.shape = DeviceCollider::sphere;
          for (int a = 0; a < 3; ++a) d.a[a] = shape.center()[a];
          d.b[0] = shape.radius();
        } else {
          refused = "a cylinder or level-set collider";
        }
      },
      c.shape());
  if (!c.angular_velocity().isZero(0.0)) refused = "a turning collider";
  for (int a = 0; a < 3; ++a) d.velocity[a] = c.velocity()[a];
  d.translating = c.motion() == geometry::Motion::translating;
  d.hollow = c.hollow();
  d.until = std::isfinite(c.until()) ? c.until() : 1e300;
  d.contact = static_cast<int>(c.contact().type);
  d.friction = c.contact().friction;
  return d;
}

std::string gib(double bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.2f GiB", bytes / 1073741824.0);
  return text;
}

//! The stage that runs the explicit step on the device.
class DeviceStep final : public Stage<MpmState<3>> {
public:
  explicit DeviceStep(std::unique_ptr<detail::DeviceSolid> device) : device_(std::move(device)) {}
  std::string name() const override { return "device_step"; }
  std::vector<std::string> reads() const override {
    return {"particle.x",       "particle.v",        "particle.C", "particle.mass",
            "particle.volume0", "particle.material", "particle.F", "particle.plastic"};
  }
  std::vector<std::string> writes() const override {
    return {"dt", "particle.x", "particle.v", "particle.C", "particle.F", "particle.plastic"};
  }

  void run(MpmState<3>& s) override {
    if (!uploaded_) upload(s.particles);
    s.dt = std::min(device_->stable_dt(), s.dt_limit);
    device_->step(s.dt, s.time + s.dt);
    const detail::StepTimes t = device_->last_times();
    times_ = {t.sort, t.p2g, t.grid, t.g2p};
    reorders_ += t.reordered;
    stale_ = true;
  }

  //! The host particles from the device (at frame ends and before a checkpoint).
  void synchronize(MpmState<3>& s) override {
    if (!stale_) return;
    const auto start = std::chrono::steady_clock::now();
    download(s.particles);
    download_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stale_ = false;
  }

  std::vector<Diagnostic> diagnostics() const override {
    return {{"device_sort_ms", 1e3 * times_[0]},
            {"device_p2g_ms", 1e3 * times_[1]},
            {"device_grid_ms", 1e3 * times_[2]},
            {"device_g2p_ms", 1e3 * times_[3]},
            {"device_download_ms", 1e3 * download_seconds_},
            {"device_memory_mb", device_->memory_bytes() / 1048576.0},
            {"device_reorders", double(reorders_)}};
  }

private:
  void upload(const Particles<3>& P) {
    detail::HostParticles h;
    const std::size_t n = h.n = P.size();
    const auto& F = solid::elastic_F(P);
    const auto& plastic = solid::plastic_state(P);
    h.x.resize(3 * n);
    h.v.resize(3 * n);
    h.C.resize(9 * n);
    h.F.resize(9 * n);
    for (std::size_t p = 0; p < n; ++p) {
      for (int a = 0; a < 3; ++a) h.x[a * n + p] = P.x[p][a], h.v[a * n + p] = P.v[p][a];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) h.C[(3 * r + c) * n + p] = P.C[p](r, c), h.F[(3 * r + c) * n + p] = F[p](r, c);
    }
    h.plastic = plastic;
    h.mass = P.mass;
    h.volume0 = P.volume0;
    h.material = P.material;
    device_->upload(h);
    uploaded_ = true;
    uploaded_count_ = n;
  }

  void download(Particles<3>& P) {
    if (P.size() != uploaded_count_)
      throw std::logic_error("device_step: the host holds " + std::to_string(P.size()) + " particles, the device " +
                             std::to_string(uploaded_count_) + " (host particles changed during a device run)");
    detail::HostParticles& h = staging_;  // kept: ten million particles' pages are touched once per run
    device_->download(h);
    const std::size_t n = h.n;
    auto& F = solid::elastic_F(P);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384), [&](const auto& range) {
      for (std::size_t p = range.begin(); p < range.end(); ++p) {
        for (int a = 0; a < 3; ++a) P.x[p][a] = h.x[a * n + p], P.v[p][a] = h.v[a * n + p];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) P.C[p](r, c) = h.C[(3 * r + c) * n + p], F[p](r, c) = h.F[(3 * r + c) * n + p];
      }
    });
    solid::plastic_state(P) = h.plastic;
    // The CPU stages' stress cache is theirs: unknown, so that a CPU step recomputes it.
    if (auto* cache = solid::stress_cache(P)) std::fill(cache->begin(), cache->end(), Mat<3>::Constant(std::nan("")));
  }

  std::unique_ptr<detail::DeviceSolid> device_;
  detail::HostParticles staging_;  //!< the download's buffers, reused frame after frame
  bool uploaded_ = false;
  std::size_t uploaded_count_ = 0;
  bool stale_ = false;  //!< the host particles are behind the device's
  std::array<double, 4> times_{};
  double download_seconds_ = 0;  //!< wall time of the last synchronize [s]
  long long reorders_ = 0;       //!< steps that moved the particle data into block order, so far
};

std::unique_ptr<Stage<MpmState<3>>> make_device_step(const solid::SolidScene<3>& solid, const Device& device,
                                                     const Config& scene) {
  const auto refuse = [&](const std::string& what) {
    scene.fail("device", "the CUDA step does not run " + what + " (docs/gpu.md lists what it runs; use device: cpu)");
  };
  const MpmState<3>& s = solid.state;
  if (s.adaptive) refuse("adaptive grids");
  if (s.domains) refuse("particle domains");
  if (solid.solver->name() != "explicit") refuse("the " + solid.solver->name() + " solver");
  if (!std::holds_alternative<QuadraticBSpline>(s.kernel)) refuse("the " + kernel_name(s.kernel) + " kernel");
  if (s.transfer.type != TransferScheme::Type::apic) refuse("FLIP or PIC transfers");
  if (s.grid.is_periodic()) refuse("periodic axes");
  if (!s.particles.has_channel(solid::kElasticF)) refuse("particles without F");

  DeviceScene d;
  for (int a = 0; a < 3; ++a) {
    d.origin[a] = s.grid.origin()[a];
    d.node_counts[a] = s.grid.node_counts()[a];
    d.gravity[a] = s.gravity[a];
  }
  d.dx = s.grid.dx();
  const auto dt = stages::time_step_settings(solid.settings, solid.solver->wave_speed());
  d.cfl = dt.cfl;
  d.wave_cfl = dt.wave_cfl;
  d.wave_speed = dt.wave_speed;
  d.max_dt = dt.max_dt;
  for (const Material<3>& m : solid.materials) {
    std::string refused;
    d.materials.push_back(device_material(m, refused));
    if (!refused.empty()) refuse(refused + " (material '" + m.name + "')");
  }
  for (const std::uint16_t m : s.particles.material)
    if (m >= solid.materials.size()) refuse("stress-free particles");
  for (const geometry::Collider<3>& c : solid.colliders.colliders()) {
    std::string refused;
    d.colliders.push_back(device_collider(c, refused));
    if (!refused.empty()) refuse(refused);
  }
  if (const auto& walls = solid.colliders.walls()) {
    d.walls.present = true;
    d.walls.layer = walls->thickness() * (1.0 + 1e-9);  // as DomainWalls::project
    for (int a = 0; a < 3; ++a) {
      d.walls.lo[a] = walls->lo()[a];
      d.walls.hi[a] = walls->hi()[a];
      for (int side = 0; side < 2; ++side)
        if (const auto& c = walls->wall(a, side ? geometry::Side::upper : geometry::Side::lower)) {
          d.walls.contact[2 * a + side] = static_cast<int>(c->type);
          d.walls.friction[2 * a + side] = c->friction;
        }
    }
  }

  if (const std::string why = unavailable_reason(); !why.empty()) scene.fail("device", "cuda: " + why);
  // Memory: the particles, the block table of the domain, and at most 8 blocks per block that
  // holds particles now (the particles spread later, so the check leaves a quarter free).
  std::unordered_set<long long> blocks;
  for (const Vec<3>& x : s.particles.x) {
    long long key = 0;
    for (int a = 2; a >= 0; --a)
      key = key * 1000003 + static_cast<long long>(std::floor(((x[a] - d.origin[a]) / d.dx - 0.5) / 4.0));
    blocks.insert(key);
  }
  double table = 1.0;
  for (int a = 0; a < 3; ++a) table *= (d.node_counts[a] + 3) / 4;
  const bool single = device.single_precision;
  const double need = double(s.particles.size()) * detail::bytes_per_particle(single) +
                      table * double(detail::bytes_per_table_entry()) +
                      std::min(8.0 * blocks.size(), table) * detail::bytes_per_block(single);
  const double free = double(detail::device_free_bytes());
  if (need > 0.75 * free)
    scene.fail("device", "cuda: the scene needs about " + gib(need) + " of GPU memory (" +
                             std::to_string(s.particles.size()) + " particles in " + (single ? "single" : "double") +
                             " precision), more than three quarters of the " + gib(free) + " free on " +
                             detail::device_description());
  return std::make_unique<DeviceStep>(detail::make_device_solid(d, single));
}

}  // namespace

template <int dim>
Pipeline<MpmState<dim>> make_solid_pipeline(const solid::SolidScene<dim>& solid, const Device& device,
                                            const Config& scene) {
  if (!device.cuda) return solid::make_solid_pipeline(solid);
  if constexpr (dim != 3) {
    scene.fail("device", "the CUDA step runs 3D scenes; this scene is " + std::to_string(dim) + "D");
  } else {
    Pipeline<MpmState<3>> p(particle_fields(solid.state.particles));
    p.add(make_device_step(solid, device, scene));
    return p;
  }
}

template Pipeline<MpmState<2>> make_solid_pipeline(const solid::SolidScene<2>&, const Device&, const Config&);
template Pipeline<MpmState<3>> make_solid_pipeline(const solid::SolidScene<3>&, const Device&, const Config&);

}  // namespace mpm::cuda
