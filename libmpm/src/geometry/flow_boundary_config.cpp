#include <mpm/core/number_text.h>
#include <mpm/geometry/flow_boundary_config.h>

#include <mpm/core/error.h>
#include <mpm/core/kernels.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/seeding.h>

#include <cmath>

namespace mpm::geometry {

namespace {

template <int dim>
std::vector<Face> faces() {
  std::vector<Face> f;
  for (int axis = 0; axis < dim; ++axis)
    for (const Side side : {Side::lower, Side::upper}) f.push_back({axis, side});
  return f;
}

//! The `face` key of a flow map; it must be open (no wall key, or `open`) and not periodic.
template <int dim>
Face parse_face(const Config& flow, const Config& scene, const SceneSettings<dim>& settings) {
  const std::string name = flow.text("face");
  std::string names;
  for (const Face& f : faces<dim>()) {
    if (face_name(f) != name) {
      names += (names.empty() ? "" : ", ") + face_name(f);
      continue;
    }
    if (const std::optional<Config> walls = scene.optional_child("walls"); walls && walls->has(name))
      if (const std::string wall = walls->text(name); wall != "open")
        flow.fail("face", "the face is closed by walls." + name + " = " + wall +
                              "; a flow boundary needs it open (remove that key or set it to open)");
    if (settings.periodic[f.axis]) flow.fail("face", "lies on a periodic axis (key periodic)");
    return f;
  }
  flow.fail("face", "expected one of " + names);
}

//! +1 for a lower face (the domain lies towards +axis), -1 for an upper one.
double inward(const Face& f) { return f.side == Side::lower ? 1.0 : -1.0; }

}  // namespace

std::string face_name(const Face& face) {
  return std::string(1, "xyz"[face.axis]) + (face.side == Side::lower ? "_min" : "_max");
}

template <int dim>
FlowBoundaries<dim> parse_flow_boundaries(const Config& scene, const SceneSettings<dim>& settings) {
  FlowBoundaries<dim> flow;
  const double layer = wall_layer(settings.kernel, settings.dx);
  if (const std::optional<Config> out = scene.optional_child("outflow"))
    flow.outflow = parse_face<dim>(*out, scene, settings);
  const std::optional<Config> in = scene.optional_child("inflow");
  if (!in) return flow;

  Inflow<dim> inflow;
  inflow.face = parse_face<dim>(*in, scene, settings);
  const int a = inflow.face.axis;
  if (flow.outflow && flow.outflow->axis == a && flow.outflow->side == inflow.face.side)
    in->fail("face", "is also the outflow face");
  inflow.velocity = in->vector<dim>("velocity");
  int largest = 0;
  inflow.velocity.cwiseAbs().maxCoeff(&largest);
  if (largest != a || !(inward(inflow.face) * inflow.velocity[a] > 0.0))
    in->fail("velocity", "must enter the domain through " + face_name(inflow.face) + ": its largest component is " +
                             (inward(inflow.face) > 0 ? "+" : "-") + std::string(1, "xyz"[a]));

  inflow.lo = in->vector<dim>("lo");
  inflow.hi = in->vector<dim>("hi");
  if (!(inflow.hi.array() > inflow.lo.array()).all()) in->fail("hi", "must exceed lo in every component");
  require_inside_domain(*in, inflow.lo, inflow.hi, settings);
  // The inlet spans the open layer of its face and at least one cell beyond, where the stream enters.
  const bool lower = inflow.face.side == Side::lower;
  const double open_end = lower ? settings.domain_lo[a] + layer : settings.domain_hi[a] - layer;
  if (lower ? inflow.lo[a] > open_end : inflow.hi[a] < open_end)
    in->fail(lower ? "lo" : "hi", "the inlet must start within the open layer of " + face_name(inflow.face) +
                                      " (wall_layer = " + std::to_string(layer) + " m from the face)");
  if (lower ? inflow.hi[a] < open_end + settings.dx : inflow.lo[a] > open_end - settings.dx)
    in->fail(lower ? "hi" : "lo", "the inlet must reach at least one cell (dx = " + std::to_string(settings.dx) +
                                      " m) beyond the open layer of its face");
  inflow.particles_per_cell = particles_per_cell<dim>(*in);
  try {
    stages::ParticleSource<dim>(inflow_source(inflow, settings, 1.0));
  } catch (const InputError& e) {
    in->fail("lo", e.what());
  }
  flow.inflow = inflow;
  return flow;
}

template <int dim>
void add_flow_boundaries(const FlowBoundaries<dim>& flow, ColliderSet<dim>& colliders) {
  if (colliders.walls()) {
    DomainWalls<dim> walls = *colliders.walls();
    if (flow.outflow) walls.set_wall(flow.outflow->axis, flow.outflow->side, std::nullopt);
    if (flow.inflow) walls.set_wall(flow.inflow->face.axis, flow.inflow->face.side, std::nullopt);
    colliders.set_walls(walls);
  }
  if (flow.inflow)
    colliders.add(Collider<dim>(Box<dim>(flow.inflow->lo, flow.inflow->hi), Contact{ContactType::sticky, 0.0},
                                flow.inflow->velocity, Motion::fixed));
}

template <int dim>
typename stages::ParticleSource<dim>::Settings inflow_source(const Inflow<dim>& inflow,
                                                             const SceneSettings<dim>& settings, double density) {
  const int a = inflow.face.axis;
  const double layer = wall_layer(settings.kernel, settings.dx);
  const double h = settings.dx / lattice_points_per_axis<dim>(inflow.particles_per_cell);
  typename stages::ParticleSource<dim>::Settings s;
  s.lo = inflow.lo;
  s.hi = inflow.hi;
  // Half a spacing past the sink of the face, so no particle is emitted onto it.
  if (inflow.face.side == Side::lower)
    s.lo[a] = settings.domain_lo[a] + layer + 0.5 * h;
  else
    s.hi[a] = settings.domain_hi[a] - layer - 0.5 * h;
  s.velocity = inflow.velocity;
  s.dx = settings.dx;
  s.particles_per_cell = inflow.particles_per_cell;
  s.particle_volume = particle_volume<dim>(settings.dx, inflow.particles_per_cell);
  s.particle_mass = density * s.particle_volume;
  return s;
}

template <int dim>
std::vector<stages::SinkRegion<dim>> flow_sink_regions(const FlowBoundaries<dim>& flow,
                                                       const SceneSettings<dim>& settings) {
  const double layer = wall_layer(settings.kernel, settings.dx);
  std::vector<stages::SinkRegion<dim>> regions;
  for (const std::optional<Face>& f :
       {flow.outflow, flow.inflow ? std::optional<Face>(flow.inflow->face) : std::optional<Face>()})
    if (f) regions.push_back(stages::face_region<dim>(settings.domain_lo, settings.domain_hi, f->axis, f->side, layer));
  return regions;
}

template <int dim>
void require_inside_domain(const Config& at, const Vec<dim>& lo, const Vec<dim>& hi,
                           const SceneSettings<dim>& settings) {
  const auto box = [&] {
    std::string text = "must lie inside the domain, from";
    for (const Vec<dim>* corner : {&settings.domain_lo, &settings.domain_hi}) {
      for (int a = 0; a < dim; ++a) text += (a == 0 ? " [" : ", ") + number_text((*corner)[a]);
      text += corner == &settings.domain_lo ? "] to" : "]";
    }
    return text;
  };
  if ((lo.array() < settings.domain_lo.array()).any()) at.fail("lo", box());
  if ((hi.array() > settings.domain_hi.array()).any()) at.fail("hi", box());
}

#define MPM_FLOW_BOUNDARIES(dim)                                                                                       \
  template void require_inside_domain(const Config&, const Vec<dim>&, const Vec<dim>&, const SceneSettings<dim>&);     \
  template FlowBoundaries<dim> parse_flow_boundaries(const Config&, const SceneSettings<dim>&);                        \
  template void add_flow_boundaries(const FlowBoundaries<dim>&, ColliderSet<dim>&);                                    \
  template stages::ParticleSource<dim>::Settings inflow_source(const Inflow<dim>&, const SceneSettings<dim>&, double); \
  template std::vector<stages::SinkRegion<dim>> flow_sink_regions(const FlowBoundaries<dim>&,                          \
                                                                  const SceneSettings<dim>&);
MPM_FLOW_BOUNDARIES(2)
MPM_FLOW_BOUNDARIES(3)

}  // namespace mpm::geometry
