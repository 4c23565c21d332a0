// solid_scene: runs any generic solid scene file (materials, bodies, colliders, walls) with
// the explicit elastoplastic pipeline (on the CPU, or on a GPU with `device: cuda`,
// mpm/cuda/device_pipeline.h); the scene-specific apps add their own keys and results.
//
//   solid_scene data/scenes/jello_collide.yaml --set time.end=0.05
//
// summary.json: energy_growth, the largest total energy (kinetic + elastic + gravity) over
// the run minus the initial one, relative to the energy the scene can release: the initial
// kinetic and elastic energy plus the potential energy above the lowest point of the domain
// along gravity (M g h, h the height of the centre of mass above the floor) -- positive growth
// means the step created energy; energy_scale, that energy [J]. The scale does not depend on where the origin is (the total
// energy m g y measured from y = 0 let a scene 100 m up grow 300 times more). --check asserts
// the growth stays below 2 %. With the scene key rest_state: true (one body of an elastic
// material; bodies of plastic materials, such as a snowball thrown at it, are left out), also
// rest_state_error: the distance of that body from its rest shape after shape matching (Zhu et
// al., Table 1; solid/rest_state.h).
#include <mpm/core/app.h>
#include <mpm/core/runner.h>
#include <mpm/cuda/device_pipeline.h>
#include <mpm/solid/rest_state.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>

#include <algorithm>
#include <cmath>

using namespace mpm;

namespace {

template <class T>
std::vector<T> gather(const std::vector<T>& values, const std::vector<std::size_t>& at) {
  std::vector<T> out;
  out.reserve(at.size());
  for (const std::size_t i : at) out.push_back(values[i]);
  return out;
}

template <int dim>
int run(const CommandLine& cl, const Config& scene) {
  solid::SolidScene<dim> solid = solid::load_solid_scene<dim>(scene);
  // rest_state: true: one elastic body seeded at rest or homogeneously stretched; each of its
  // particles carries its rest position, the others NaN (a channel, so that sorting, resampling
  // and restarts keep the pairing).
  const bool rest_state = scene.flag("rest_state", false);
  Particles<dim>& P = solid.state.particles;
  const std::vector<Mat<dim>>* F = P.template find_channel<Mat<dim>>(solid::kElasticF);
  const auto elastic_material = [&](std::size_t m) {
    return std::holds_alternative<plasticity::NoPlasticity>(solid.materials[m].plasticity);
  };
  std::size_t elastic_bodies = 0;
  for (const Config& body : scene.has("bodies") ? scene.list("bodies") : std::vector<Config>{})
    elastic_bodies += elastic_material(solid::material_index(solid.materials, body.text("material"), body, "material"));
  if (rest_state && (elastic_bodies != 1 || !F))
    scene.fail("rest_state", "the rest-state error needs exactly one body of an elastic material (" +
                                 std::to_string(elastic_bodies) +
                                 " here) and a solver that tracks F (explicit or implicit)");
  // The elastic body's particles (a particle keeps its material).
  const auto elastic_particles = [&] {
    std::vector<std::size_t> body;
    for (std::size_t p = 0; p < P.size(); ++p)
      if (elastic_material(P.material[p])) body.push_back(p);
    return body;
  };
  if (rest_state) {
    const std::vector<std::size_t> body = elastic_particles();
    const auto rest = solid::rest_shape(gather(P.x, body), gather(*F, body), gather(P.mass, body));
    auto& X =
        P.template add_channel<Vec<dim>>("rest_position", Vec<dim>::Constant(std::nan("")), ChannelUse{false, true});
    for (std::size_t i = 0; i < body.size(); ++i) X[body[i]] = rest[i];
  }
  const cuda::Device device = cuda::parse_device(scene);
  scene.reject_unknown_keys();
  auto pipeline = cuda::make_solid_pipeline(solid, device, scene);
  Runner<dim> runner("solid_scene", cl, scene, solid.settings);
  runner.set_elastic_energy([&](const MpmState<dim>& s) { return solid::elastic_energy(s, solid.materials); });
  runner.run(solid.state, pipeline);

  const auto kinetic = runner.history("kinetic_energy"), elastic = runner.history("elastic_energy"),
             gravity = runner.history("gravity_potential");
  double largest = -1e300;
  for (std::size_t f = 0; f < kinetic.size(); ++f) largest = std::max(largest, kinetic[f] + elastic[f] + gravity[f]);
  const double initial = kinetic[0] + elastic[0] + gravity[0];
  // The potential at the lowest corner of the domain along g (gravity_potential = -sum m g.x).
  const Vec<dim>&lo = solid.settings.domain_lo, &hi = solid.settings.domain_hi;
  double floor = 1e300;
  for (int corner = 0; corner < (1 << dim); ++corner) {
    Vec<dim> x;
    for (int a = 0; a < dim; ++a) x[a] = (corner >> a) & 1 ? hi[a] : lo[a];
    floor = std::min(floor, -solid.settings.gravity.dot(x));
  }
  const double releasable = std::max(gravity[0] - runner.history("mass")[0] * floor, 0.0);
  const double scale = std::max(kinetic[0] + elastic[0] + releasable, 1e-300);
  const double growth = (largest - initial) / scale;
  std::vector<std::pair<std::string, double>> summary{
      {"energy_growth", growth}, {"energy_scale", scale}, {"particles", double(solid.state.particles.size())}};
  if (rest_state) {
    const std::vector<Vec<dim>>& X = P.template channel<Vec<dim>>("rest_position");
    const std::vector<std::size_t> body = elastic_particles();
    summary.emplace_back("rest_state_error",
                         solid::rest_state_error(gather(X, body), gather(P.x, body), gather(P.mass, body)));
  }
  runner.write_summary(summary);
  if (cl.check) return check_value("energy_growth", std::max(growth, 0.0), 0.0, 0.02) ? 0 : 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_scene_app(argc, argv, "solid_scene", "Any generic solid scene", run<2>, run<3>);
}
