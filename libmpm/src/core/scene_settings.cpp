#include <mpm/core/scene_settings.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace mpm {

template <int dim>
int SceneSettings<dim>::frame_count() const {
  return static_cast<int>(std::llround(std::ceil(end_time / frame_dt - 1e-9)));
}

namespace {
template <int dim>
std::string point_text(const Vec<dim>& x) {
  std::ostringstream s;
  s << "(";
  for (int a = 0; a < dim; ++a) s << (a ? ", " : "") << x[a];
  s << ")";
  return s.str();
}
}  // namespace

template <int dim>
OutsideDomain first_outside_domain(const SceneSettings<dim>& settings, const std::vector<Vec<dim>>& positions) {
  for (const Vec<dim>& x : positions)
    for (int a = 0; a < dim; ++a)
      if (!(x[a] >= settings.domain_lo[a] &&
            (settings.periodic[a] ? x[a] < settings.domain_hi[a] : x[a] <= settings.domain_hi[a])))
        return {"a particle at " + point_text<dim>(x) + " lies outside the domain " +
                    point_text<dim>(settings.domain_lo) + " - " + point_text<dim>(settings.domain_hi),
                x[a] < settings.domain_lo[a]};
  return {};
}

int scene_dimension(const Config& scene) { return scene.integer("dim", 2, 2, 3); }

Kernel parse_kernel(const Config& scene) {
  const std::optional<Config> grid = scene.optional_child("grid");
  if (!grid) return QuadraticBSpline{};
  const std::string kernel = grid->choice("kernel", "quadratic", {"quadratic", "cubic", "ugimp"});
  if (kernel == "quadratic") return QuadraticBSpline{};
  if (kernel == "cubic") return CubicBSpline{};
  return UGimp{0.5 * grid->number("particle_size", 1.0, Range{0.0, 1.0, true, false})};
}

namespace {
//! The optional `periodic` flags; each periodic axis must hold whole cells and no wall faces.
template <int dim>
std::array<bool, dim> parse_periodic(const Config& scene, const SceneSettings<dim>& s) {
  std::array<bool, dim> periodic{};
  const std::vector<std::string> flags = scene.texts("periodic");
  if (flags.empty()) return periodic;
  if (flags.size() != static_cast<std::size_t>(dim))
    scene.fail("periodic",
               "needs one flag per axis (" + std::to_string(dim) + "), got " + std::to_string(flags.size()));
  const std::optional<Config> walls = scene.optional_child("walls");
  for (int a = 0; a < dim; ++a) {
    if (flags[a] != "true" && flags[a] != "false")
      scene.fail("periodic", "entry " + std::to_string(a) + " is '" + flags[a] + "' (accepted: true, false)");
    periodic[a] = flags[a] == "true";
    if (!periodic[a]) continue;
    const double cells = (s.domain_hi[a] - s.domain_lo[a]) / s.dx;
    if (std::abs(cells - std::round(cells)) > 1e-9 * cells || std::round(cells) < 4)
      scene.fail("periodic", std::string("axis ") + "xyz"[a] +
                                 " is periodic, so hi - lo must be a whole number (>= 4) of cells dx; it is " +
                                 std::to_string(cells) + " cells");
    if (!walls) continue;
    const std::string contact = walls->text("contact", "separate");  // parse_contact's default
    for (const char* side : {"_min", "_max"}) {
      const std::string key = std::string(1, "xyz"[a]) + side;
      if (walls->text(key, contact) != "open")
        walls->fail(key, std::string("axis ") + "xyz"[a] + " is periodic: it has no walls (set " + key + ": open)");
    }
  }
  return periodic;
}
}  // namespace

template <int dim>
SceneSettings<dim> parse_scene_settings(const Config& scene, const std::optional<DerivedDomain<dim>>& derived) {
  SceneSettings<dim> s;
  if (derived) {
    s.domain_lo = derived->lo;
    s.domain_hi = derived->hi;
    s.dx = derived->dx;
  } else {
    const Config domain = scene.child("domain");
    s.domain_lo = domain.vector<dim>("lo");
    s.domain_hi = domain.vector<dim>("hi");
    for (int a = 0; a < dim; ++a)
      if (s.domain_hi[a] <= s.domain_lo[a]) domain.fail("hi", "must exceed domain.lo on every axis");
    s.dx = scene.child("grid").number("dx", Range::positive());
  }
  s.periodic = parse_periodic<dim>(scene, s);
  s.kernel = parse_kernel(scene);

  if (auto transfer = scene.optional_child("transfer")) {
    const std::string scheme = transfer->choice("scheme", "apic", {"apic", "flip"});
    s.transfer.type = scheme == "apic" ? TransferScheme::Type::apic : TransferScheme::Type::flip;
    if (s.transfer.type == TransferScheme::Type::flip)
      s.transfer.flip_ratio = transfer->number("flip_ratio", 0.95, Range::closed(0.0, 1.0));
  }

  const Config time = scene.child("time");
  s.end_time = time.number("end", Range::positive());
  s.frame_dt = time.number("frame_dt", 0.02, Range::positive());
  // Frame numbers are int (file names, checkpoints): bound the count before it is computed, so a
  // huge time.end / frame_dt is refused instead of overflowing into a run of no frames.
  if (const double frames = std::ceil(s.end_time / s.frame_dt - 1e-9); !(frames <= kMaxFrames)) {
    char count[32];
    std::snprintf(count, sizeof count, "%.6g", frames);
    time.fail("frame_dt", "time.end / time.frame_dt gives " + std::string(count) + " frames; at most " +
                              std::to_string(kMaxFrames) + " (raise frame_dt or lower end)");
  }
  s.cfl = time.number("cfl", 0.4, Range{0.0, 1.0, true, false});
  s.wave_cfl = time.number("wave_cfl", 0.5, Range{0.0, 1.0, true, false});
  s.max_dt = time.number("max_dt", 1e300, Range::positive());
  s.max_steps_per_frame = time.integer("max_steps_per_frame", 200000, 1, 1000000000);

  Vec<dim> g = Vec<dim>::Zero();
  g[1] = -9.81;  // y is up in 2D and 3D (previews, apps and walls follow this convention)
  s.gravity = scene.vector<dim>("gravity", g);

  if (auto out = scene.optional_child("output")) {
    s.output.particles = out->flag("particles", true);
    s.output.png = out->flag("png", true);
    s.output.color_by = out->choice("color_by", "speed", {"speed", "material", "J", "plastic", "height", "level"});
    s.output.png_width = out->integer("png_width", 640, 16, 8192);
    s.output.checkpoint_every = out->integer("checkpoint_every", 0, 0, 1000000);
    s.output.checkpoint_minutes = out->number("checkpoint_minutes", 10.0, Range::closed(0.0, 1e6));
    s.output.checkpoints_kept = out->integer("checkpoints_kept", 2, 1, 1000000);
  }
  return s;
}

template OutsideDomain first_outside_domain(const SceneSettings<2>&, const std::vector<Vec<2>>&);
template OutsideDomain first_outside_domain(const SceneSettings<3>&, const std::vector<Vec<3>>&);
template struct SceneSettings<2>;
template struct SceneSettings<3>;
template SceneSettings<2> parse_scene_settings<2>(const Config&, const std::optional<DerivedDomain<2>>&);
template SceneSettings<3> parse_scene_settings<3>(const Config&, const std::optional<DerivedDomain<3>>&);

}  // namespace mpm
