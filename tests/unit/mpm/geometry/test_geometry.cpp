// Collision objects and particle seeding: exact signed distances, contact laws, scene parsing,
// mesh level sets and lattice seeding.
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/geometry/body_gap.h>
#include <mpm/geometry/collider.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/level_set.h>
#include <mpm/geometry/particle_spacing.h>
#include <mpm/geometry/seeding.h>
#include <mpm/geometry/signed_distance.h>
#include <mpm/geometry/triangle_mesh.h>

#include <doctest/doctest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <variant>

using namespace mpm;
using namespace mpm::geometry;

namespace {

//! A file in a fresh temporary folder of this test process.
std::string temp_file(const std::string& name) {
  static const std::filesystem::path folder = [] {
    std::filesystem::path p =
        std::filesystem::temp_directory_path() / ("mpm_test_geometry_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(p);
    return p;
  }();
  return (folder / name).string();
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = temp_file(name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

//! The unit cube [0, 1]^3 as six outward quads, written with negative (relative) indices and
//! v/t/n corners to exercise the OBJ reader.
const char* kUnitCubeObj = R"(# unit cube
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vn 0 0 1
f -8/1/1 -5/1/1 -6/1/1 -7/1/1
f 5 6 7 8
f 1//1 2//1 6//1 5//1
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

template <int dim, class ShapeT>
Vec<dim> gradient_by_differences(const ShapeT& shape, const Vec<dim>& x, double h) {
  Vec<dim> g;
  for (int i = 0; i < dim; ++i) {
    const Vec<dim> step = h * Vec<dim>::Unit(i);
    g[i] = (shape.phi(Vec<dim>(x + step)) - shape.phi(Vec<dim>(x - step))) / (2 * h);
  }
  return g;
}

//! At random points away from kinks (`smooth_at`), |grad phi| = 1 by central differences and
//! normal() equals that gradient.
template <int dim, class ShapeT, class Smooth>
void check_eikonal(const ShapeT& shape, const Vec<dim>& lo, const Vec<dim>& hi, Smooth smooth_at) {
  std::mt19937_64 rng(7);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Vec<dim> x;
    for (int i = 0; i < dim; ++i) x[i] = lo[i] + (hi[i] - lo[i]) * double(rng() >> 11) * 0x1.0p-53;
    if (!smooth_at(x)) continue;
    const Vec<dim> g = gradient_by_differences<dim>(shape, x, 1e-6);
    CHECK(g.norm() == doctest::Approx(1.0).epsilon(1e-6));
    CHECK((shape.normal(x) - g).norm() < 1e-5);
    ++checked;
  }
  CHECK(checked > 100);
}

bool well_separated(double a, double b, double margin = 1e-3) { return std::abs(a - b) > margin; }

//! Second largest coefficient of a vector.
template <int dim>
double second_largest(Vec<dim> v) {
  int top = 0;
  v.maxCoeff(&top);
  v[top] = -1e300;
  return v.maxCoeff();
}

}  // namespace

TEST_CASE("half space: signed distance and normal") {
  const HalfSpace<2> floor(Vec<2>(0.0, 0.1), Vec<2>(0.0, 2.0));
  CHECK(floor.phi(Vec<2>(3.0, 0.4)) == doctest::Approx(0.3));
  CHECK(floor.phi(Vec<2>(-1.0, 0.0)) == doctest::Approx(-0.1));
  CHECK((floor.normal(Vec<2>(5.0, 5.0)) - Vec<2>(0.0, 1.0)).norm() == 0.0);
  const HalfSpace<3> ramp(Vec<3>(0, 0, 0), Vec<3>(1, 1, 0));
  CHECK(ramp.phi(Vec<3>(1, 1, 7)) == doctest::Approx(std::sqrt(2.0)));
  check_eikonal<3>(ramp, Vec<3>::Constant(-1), Vec<3>::Constant(1), [](const Vec<3>&) { return true; });
  CHECK_THROWS_AS(HalfSpace<2>(Vec<2>::Zero(), Vec<2>::Zero()), InputError);
}

TEST_CASE("box: exact signed distance inside and outside") {
  const Box<3> box(Vec<3>(0, 0, 0), Vec<3>(2, 1, 4));
  CHECK(box.phi(Vec<3>(1, 0.5, 2)) == doctest::Approx(-0.5));          // centre: nearest face y
  CHECK(box.phi(Vec<3>(0.1, 0.5, 2)) == doctest::Approx(-0.1));        // near face x = 0
  CHECK(box.phi(Vec<3>(3, 0.5, 2)) == doctest::Approx(1.0));           // beside a face
  CHECK(box.phi(Vec<3>(3, 2, 2)) == doctest::Approx(std::sqrt(2.0)));  // beside an edge
  CHECK(box.phi(Vec<3>(-1, -2, 6)) == doctest::Approx(3.0));           // beside a corner: sqrt(1 + 4 + 4)
  CHECK(box.phi(Vec<3>(2, 0.3, 1)) == doctest::Approx(0.0));
  CHECK((box.normal(Vec<3>(1.9, 0.5, 2)) - Vec<3>(1, 0, 0)).norm() < 1e-14);
  CHECK((box.normal(Vec<3>(-0.5, 0.5, 5)) - Vec<3>(-0.5, 0, 1).normalized()).norm() < 1e-14);
  // Inside, the kinks are where the two deepest faces are equally near.
  const Vec<3> half(1, 0.5, 2), center(1, 0.5, 2);
  check_eikonal<3>(box, Vec<3>(-1, -1, -1), Vec<3>(3, 2, 5), [&](const Vec<3>& x) {
    const Vec<3> q = (x - center).cwiseAbs() - half;
    return q.maxCoeff() > 1e-3 || well_separated(q.maxCoeff(), second_largest<3>(q));
  });
  const Box<2> rect(Vec<2>(0, 0), Vec<2>(1, 1));
  CHECK(rect.phi(Vec<2>(2, 2)) == doctest::Approx(std::sqrt(2.0)));
  CHECK(rect.phi(Vec<2>(0.25, 0.5)) == doctest::Approx(-0.25));
  CHECK_THROWS_AS(Box<2>(Vec<2>(0, 0), Vec<2>(1, 0)), InputError);
}

TEST_CASE("sphere and cylinder: exact signed distance") {
  const Sphere<3> ball(Vec<3>(1, 2, 3), 0.5);
  CHECK(ball.phi(Vec<3>(1, 2, 3)) == doctest::Approx(-0.5));
  CHECK(ball.phi(Vec<3>(1, 2, 5)) == doctest::Approx(1.5));
  check_eikonal<3>(ball, Vec<3>(0, 1, 2), Vec<3>(2, 3, 4),
                   [&](const Vec<3>& x) { return (x - Vec<3>(1, 2, 3)).norm() > 1e-3; });

  const Cylinder<3> rod(Vec<3>(0, 0, 0), Vec<3>(0, 0, 2), 1.0);
  CHECK(rod.phi(Vec<3>(3, 0, 100)) == doctest::Approx(2.0));
  CHECK(rod.phi(Vec<3>(0, 0.25, -7)) == doctest::Approx(-0.75));
  CHECK((rod.normal(Vec<3>(0, -2, 5)) - Vec<3>(0, -1, 0)).norm() < 1e-14);

  const Cylinder<3> can(Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), 1.0, 2.0);
  CHECK(can.phi(Vec<3>(0, 0, 0)) == doctest::Approx(-1.0));
  CHECK(can.phi(Vec<3>(1.8, 0, 0)) == doctest::Approx(-0.2));  // nearer the cap than the side
  CHECK(can.phi(Vec<3>(3, 0, 0.5)) == doctest::Approx(1.0));
  CHECK(can.phi(Vec<3>(5, 0, 5)) == doctest::Approx(5.0));  // rim: sqrt(3^2 + 4^2)
  CHECK((can.normal(Vec<3>(-2.5, 0.1, 0.2)) - Vec<3>(-1, 0, 0)).norm() < 1e-14);
  check_eikonal<3>(can, Vec<3>(-3, -2, -2), Vec<3>(3, 2, 2), [](const Vec<3>& x) {
    const double rho = x.tail<2>().norm();
    const Vec<2> q(rho - 1.0, std::abs(x[0]) - 2.0);
    return rho > 1e-3 && (q.maxCoeff() > 1e-3 || well_separated(q[0], q[1]));
  });

  const Cylinder<2> disk(Vec<2>(1, 1), 0.5);
  CHECK(disk.phi(Vec<2>(1, 3)) == doctest::Approx(1.5));
  CHECK(disk.phi(Vec<2>(1.25, 1)) == doctest::Approx(-0.25));
  check_eikonal<2>(disk, Vec<2>(0, 0), Vec<2>(2, 2), [](const Vec<2>& x) { return (x - Vec<2>(1, 1)).norm() > 1e-3; });
  CHECK_THROWS_AS(Sphere<2>(Vec<2>::Zero(), 0.0), InputError);
}

TEST_CASE("contact laws") {
  const Vec<3> n(0, 0, 1);
  const Vec<3> approaching(3, 0, -1);  // |v_t| = 3, v_n = -1
  SUBCASE("sticky stops the relative motion") {
    CHECK(Contact{ContactType::sticky, 0.0}.apply<3>(approaching, n).norm() == 0.0);
  }
  SUBCASE("slip removes the normal part and keeps the tangential part") {
    const Vec<3> v = Contact{ContactType::slip, 0.0}.apply<3>(approaching, n);
    CHECK(v.dot(n) == 0.0);
    CHECK((v - Vec<3>(3, 0, 0)).norm() == 0.0);
    CHECK((Contact{ContactType::slip, 0.0}.apply<3>(Vec<3>(1, 2, 5), n) - Vec<3>(1, 2, 0)).norm() == 0.0);
  }
  SUBCASE("a material point may leave a slip obstacle; sticky still holds it") {
    const Contact slip{ContactType::slip, 0.0};
    const Vec<3> leaving(1, 2, 5);
    CHECK((slip.apply<3>(leaving, n, ContactPoint::material) - leaving).norm() == 0.0);
    CHECK((slip.apply<3>(approaching, n, ContactPoint::material) - Vec<3>(3, 0, 0)).norm() == 0.0);
    CHECK(Contact{ContactType::sticky, 0.0}.apply<3>(leaving, n, ContactPoint::material).norm() == 0.0);
  }
  SUBCASE("separate leaves separating velocities alone") {
    const Vec<3> leaving(3, 1, 2);
    CHECK((Contact{ContactType::separate, 0.5}.apply<3>(leaving, n) - leaving).norm() == 0.0);
  }
  SUBCASE("Coulomb friction reduces |v_t| by mu |v_n|") {
    const Vec<3> v = Contact{ContactType::separate, 0.5}.apply<3>(approaching, n);
    CHECK((v - Vec<3>(2.5, 0, 0)).norm() < 1e-15);
    const Vec<3> frictionless = Contact{ContactType::separate, 0.0}.apply<3>(approaching, n);
    CHECK((frictionless - Vec<3>(3, 0, 0)).norm() == 0.0);
  }
  SUBCASE("inside the friction cone the node sticks") {
    CHECK(Contact{ContactType::separate, 3.0}.apply<3>(approaching, n).norm() == 0.0);
    CHECK(Contact{ContactType::separate, 2.9}.apply<3>(approaching, n).norm() == doctest::Approx(0.1));
  }
}

TEST_CASE("collider: project only inside, relative to a moving obstacle") {
  const Vec<2> v_col(1.0, 0.0);
  const Collider<2> slab(Box<2>(Vec<2>(0, 0), Vec<2>(1, 0.5)), Contact{ContactType::sticky, 0.0}, v_col);
  // At t = 2 the box has moved to [2, 3] x [0, 0.5].
  CHECK(slab.phi(Vec<2>(2.5, 0.25), 2.0) == doctest::Approx(-0.25));
  CHECK(slab.phi(Vec<2>(0.5, 0.25), 2.0) == doctest::Approx(1.5));
  Vec<2> v(-4.0, 7.0);
  slab.project(Vec<2>(0.5, 0.25), 2.0, v);  // outside now: untouched
  CHECK((v - Vec<2>(-4.0, 7.0)).norm() == 0.0);
  slab.project(Vec<2>(2.5, 0.25), 2.0, v);
  CHECK((v - v_col).norm() == 0.0);

  // A floor rising at 1 m/s with slip contact: the node keeps its tangential velocity and
  // moves up with the floor.
  const Collider<2> floor(HalfSpace<2>(Vec<2>(0, 0), Vec<2>(0, 1)), Contact{ContactType::slip, 0.0}, Vec<2>(0, 1));
  Vec<2> w(2.0, -3.0);
  floor.project(Vec<2>(0.0, 0.9), 1.0, w);
  CHECK((w - Vec<2>(2.0, 1.0)).norm() == 0.0);
  // Separating from the moving floor faster than it rises: free.
  Vec<2> u(2.0, 1.5);
  Collider<2>(HalfSpace<2>(Vec<2>(0, 0), Vec<2>(0, 1)), Contact{}, Vec<2>(0, 1)).project(Vec<2>(0, 0.5), 1.0, u);
  CHECK((u - Vec<2>(2.0, 1.5)).norm() == 0.0);
  CHECK_THROWS_AS(Collider<2>(Sphere<2>(Vec<2>::Zero(), 1.0), Contact{ContactType::separate, -0.1}), InputError);
}

TEST_CASE("domain walls and collider sets") {
  DomainWalls<2> walls(Vec<2>(0, 0), Vec<2>(1, 1), 0.1, Contact{ContactType::separate, 0.0});
  walls.set_wall(1, Side::upper, std::nullopt);
  Vec<2> v(-1.0, -2.0);
  walls.project(Vec<2>(0.05, 0.5), v);  // left layer: normal +x, approaching
  CHECK((v - Vec<2>(0.0, -2.0)).norm() == 0.0);
  v = Vec<2>(-1.0, -2.0);
  walls.project(Vec<2>(0.05, 0.08), v);  // corner: both walls
  CHECK(v.norm() == 0.0);
  v = Vec<2>(0.5, 3.0);
  walls.project(Vec<2>(0.5, 0.95), v);  // open top
  CHECK((v - Vec<2>(0.5, 3.0)).norm() == 0.0);
  v = Vec<2>(0.5, 3.0);
  walls.project(Vec<2>(0.5, 0.5), v);  // interior
  CHECK((v - Vec<2>(0.5, 3.0)).norm() == 0.0);
  v = Vec<2>(2.0, -1.0);
  walls.project(Vec<2>(0.5, 0.02), v);
  CHECK((v - Vec<2>(2.0, 0.0)).norm() == 0.0);

  ColliderSet<2> set;
  CHECK(set.empty());
  set.add(Collider<2>(Sphere<2>(Vec<2>(0.5, 0.5), 0.125), Contact{ContactType::sticky, 0.0}, Vec<2>(0.0, 0.3)));
  set.set_walls(walls);
  CHECK_FALSE(set.uses_level_sets());
  v = Vec<2>(5.0, 5.0);
  set.project(Vec<2>(0.5, 0.55), 0.0, v);
  CHECK((v - Vec<2>(0.0, 0.3)).norm() == 0.0);

  // Where project() acts: a closed wall's layer (its inner face included, a few ulps of
  // round-off beyond it too), inside or on a collider; not the open top's layer, not outside.
  CHECK(walls.in_layer(Vec<2>(0.5, 0.1)));
  CHECK(walls.in_layer(Vec<2>(0.1 + 1e-12, 0.5)));
  CHECK(walls.in_layer(Vec<2>(0.95, 0.5)));
  CHECK_FALSE(walls.in_layer(Vec<2>(0.5, 0.95)));  // open
  CHECK_FALSE(walls.in_layer(Vec<2>(0.5, 0.5)));
  CHECK_FALSE(walls.in_layer(Vec<2>(0.1 + 1e-6, 0.5)));
  CHECK(set.prescribes(Vec<2>(0.5, 0.55), 0.0));   // inside the sphere
  CHECK(set.prescribes(Vec<2>(0.625, 0.5), 0.0));  // on it: phi = 0 exactly
  CHECK(set.prescribes(Vec<2>(0.05, 0.5), 0.0));   // a wall's layer
  CHECK_FALSE(set.prescribes(Vec<2>(0.5, 0.65), 0.0));
  CHECK_FALSE(set.prescribes(Vec<2>(0.5, 0.95), 0.0));

  // The directions an implicit solve fixes: a slip floor fixes the normal of a node whatever
  // its motion, but of a material point only while it approaches (contact.h, ContactPoint).
  ColliderSet<2> floor;
  floor.add(Collider<2>(HalfSpace<2>(Vec<2>(0, 0.2), Vec<2>(0, 1)), Contact{ContactType::slip, 0.0}));
  const Mat<2> normal_fixed = Vec<2>(1, 0) * Vec<2>(1, 0).transpose();
  const Vec<2> x(0.5, 0.1), leaving(1.0, 2.0), approaching(1.0, -2.0);
  CHECK((floor.free_directions(x, 0.0, leaving) - normal_fixed).norm() < 1e-15);
  CHECK((floor.free_directions(x, 0.0, leaving, ContactPoint::material) - Mat<2>::Identity()).norm() < 1e-15);
  CHECK((floor.free_directions(x, 0.0, approaching, ContactPoint::material) - normal_fixed).norm() < 1e-15);
  CHECK((floor.free_directions(Vec<2>(0.5, 0.3), 0.0, approaching) - Mat<2>::Identity()).norm() < 1e-15);
}

TEST_CASE("parse colliders and walls from a scene") {
  const Config scene = Config::parse(R"(
colliders:
  - {type: half_space, point: [0, 0.1], normal: [0, 3], contact: slip}
  - {type: box, lo: [0.4, 0.2], hi: [0.6, 0.3], contact: sticky, velocity: [0.5, 0]}
  - {type: sphere, center: [0.5, 0.5], radius: 0.1, friction: 0.4}
  - {type: cylinder, point: [0.2, 0.8], radius: 0.05}
walls:
  contact: slip
  thickness: 0.08
  y_max: open
  x_min: sticky
)",
                                     "scene.yaml");
  const ColliderSet<2> set = parse_colliders<2>(scene, Vec<2>(0, 0), Vec<2>(1, 1), 0.05);
  REQUIRE(set.colliders().size() == 4);
  const Collider<2>& floor = set.colliders()[0];
  CHECK(std::holds_alternative<HalfSpace<2>>(floor.shape()));
  CHECK(floor.contact().type == ContactType::slip);
  CHECK(floor.phi(Vec<2>(7, 0.5), 0.0) == doctest::Approx(0.4));
  CHECK((set.colliders()[1].velocity() - Vec<2>(0.5, 0)).norm() == 0.0);
  CHECK(set.colliders()[1].phi(Vec<2>(0.5, 0.25), 0.0) == doctest::Approx(-0.05));
  CHECK(set.colliders()[2].contact().type == ContactType::separate);
  CHECK(set.colliders()[2].contact().friction == 0.4);
  CHECK(set.colliders()[3].phi(Vec<2>(0.2, 0.9), 0.0) == doctest::Approx(0.05));
  REQUIRE(set.walls());
  CHECK(set.walls()->thickness() == 0.08);
  CHECK_FALSE(set.walls()->wall(1, Side::upper));
  CHECK(set.walls()->wall(0, Side::lower)->type == ContactType::sticky);
  CHECK(set.walls()->wall(0, Side::upper)->type == ContactType::slip);
  scene.reject_unknown_keys();

  const auto error_of = [](const std::string& yaml) {
    try {
      parse_colliders<3>(Config::parse(yaml, "bad.yaml"), Vec<3>::Zero(), Vec<3>::Ones(), 0.05);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string unknown = error_of("colliders:\n  - {type: torus, radius: 1}\n");
  CHECK(unknown.find("bad.yaml:2") != std::string::npos);
  CHECK(unknown.find("colliders[0].type") != std::string::npos);
  CHECK(unknown.find("half_space") != std::string::npos);
  CHECK(error_of("colliders:\n  - {type: sphere, center: [0, 0, 0], radius: -1}\n").find("> 0") != std::string::npos);
  CHECK(error_of("colliders:\n  - {type: box, lo: [0, 0, 0], hi: [1, 0, 1]}\n").find("colliders[0].hi") !=
        std::string::npos);
  CHECK(error_of("colliders:\n  - {type: half_space, point: [0, 0, 0], normal: [0, 0, 0]}\n").find("nonzero") !=
        std::string::npos);
  CHECK(error_of("colliders:\n  - {type: sphere, center: [0, 0, 0], radius: 1, contact: slip, friction: 0.2}\n")
            .find("separate") != std::string::npos);
  CHECK(error_of("colliders:\n  - {type: sphere, center: [0, 0, 0], radius: 1, friction: -0.2}\n").find("friction") !=
        std::string::npos);
  CHECK(error_of("colliders:\n  - {type: level_set, file: mesh.ply}\n").find("unknown extension") != std::string::npos);
  CHECK(
      error_of("colliders:\n  - {type: level_set, file: missing.obj, voxel_size: 0.01}\n").find("colliders[0].file") !=
      std::string::npos);
  CHECK(error_of("walls: {thickness: 0.6}\n").find("walls.thickness") != std::string::npos);
  CHECK(error_of("walls: {z_max: ajar}\n").find("open") != std::string::npos);
  CHECK(error_of("colliders:\n  - {type: box, lo: [0, 0, 0], hi: [1, 1, 1], angular_velocity: [0, 0, 1]}\n")
            .find("only a sphere or a cylinder can turn") != std::string::npos);
  CHECK(error_of("colliders:\n  - {type: cylinder, point: [0, 0, 0], axis: [0, 0, 1], radius: 1, "
                 "angular_velocity: [1, 0, 0]}\n")
            .find("parallel") != std::string::npos);
  CHECK(error_of("colliders:\n  - {type: sphere, center: [0, 0, 0], radius: 1, velocity: [1, 0, 0], "
                 "angular_velocity: [0, 0, 1]}\n")
            .find("cannot also translate") != std::string::npos);
  CHECK(
      error_of("colliders:\n  - {type: sphere, center: [0, 0, 0], radius: 1, until: 0}\n").find("colliders[0].until") !=
      std::string::npos);
}

TEST_CASE("a turning grip that lets go") {
  // A capped cylinder about z turning at 1 rad/s until t = 0.5 s: a sticky node inside it takes
  // omega x (x - c) before, and nothing acts on it after.
  const Config scene = Config::parse(
      "colliders:\n  - {type: cylinder, point: [0.5, 0.5, 0.2], axis: [0, 0, 1], radius: 0.2, half_length: 0.05, "
      "angular_velocity: [0, 0, 1], contact: sticky, until: 0.5}\n");
  const ColliderSet<3> set = parse_colliders<3>(scene, Vec<3>::Zero(), Vec<3>::Ones(), 0.05);
  const Collider<3>& grip = set.colliders().at(0);
  CHECK(grip.until() == 0.5);
  Vec<3> v(3.0, -1.0, 2.0);
  grip.project(Vec<3>(0.6, 0.5, 0.22), 0.5, v);
  CHECK((v - Vec<3>(0.0, 0.1, 0.0)).norm() < 1e-12);
  Vec<3> u(3.0, -1.0, 2.0);
  grip.project(Vec<3>(0.6, 0.5, 0.22), 0.5 + 1e-9, u);
  CHECK(u == Vec<3>(3.0, -1.0, 2.0));
  CHECK(grip.phi(Vec<3>(0.6, 0.5, 0.22), 0.6) == std::numeric_limits<double>::infinity());
}

TEST_CASE("a hollow turning drum") {
  // Material inside a disk of radius 0.4 about (0.5, 0.5) turning at 2 rad/s: the obstacle is
  // the outside, its normal points inward, and a sticky node takes the wall's velocity
  // omega x (x - c).
  const Config scene = Config::parse(
      "colliders:\n  - {type: sphere, center: [0.5, 0.5], radius: 0.4, hollow: true, angular_velocity: 2, "
      "contact: sticky}\n");
  const ColliderSet<2> set = parse_colliders<2>(scene, Vec<2>(0, 0), Vec<2>(1, 1), 0.05);
  const Collider<2>& drum = set.colliders().at(0);
  CHECK(drum.hollow());
  CHECK(drum.phi(Vec<2>(0.5, 0.5), 0.0) == doctest::Approx(0.4));
  CHECK(drum.phi(Vec<2>(0.5, 0.95), 0.0) == doctest::Approx(-0.05));
  CHECK((drum.normal(Vec<2>(0.5, 0.95), 0.0) - Vec<2>(0, -1)).norm() < 1e-12);
  Vec<2> v(3.0, -1.0);
  drum.project(Vec<2>(0.5, 0.95), 0.0, v);  // inside the obstacle: the wall's velocity
  CHECK((v - Vec<2>(-2.0 * 0.45, 0.0)).norm() < 1e-12);
  Vec<2> u(3.0, -1.0);
  drum.project(Vec<2>(0.5, 0.6), 0.0, u);  // inside the drum: untouched
  CHECK(u == Vec<2>(3.0, -1.0));
  CHECK(drum.speed_within(0.4) == doctest::Approx(0.8));
}

TEST_CASE("triangle meshes: OBJ and STL") {
  const TriangleMesh cube = read_triangle_mesh(write_file("cube.obj", kUnitCubeObj));
  CHECK(cube.vertices.size() == 8);
  REQUIRE(cube.triangles.size() == 12);
  // The first face used relative indices -8 -5 -6 -7 = vertices 1 4 3 2 (0-based 0 3 2 1).
  CHECK(cube.triangles[0] == std::array<std::int32_t, 3>{0, 3, 2});
  CHECK(cube.triangles[1] == std::array<std::int32_t, 3>{0, 2, 1});
  // Closed and consistently oriented: every directed edge once, with its opposite present.
  std::set<std::pair<int, int>> edges;
  double volume = 0.0;
  for (const auto& t : cube.triangles) {
    for (int k = 0; k < 3; ++k) CHECK(edges.insert({t[k], t[(k + 1) % 3]}).second);
    volume += cube.vertices[t[0]].dot(cube.vertices[t[1]].cross(cube.vertices[t[2]])) / 6.0;
  }
  for (const auto& [a, b] : edges) CHECK(edges.count({b, a}) == 1);
  CHECK(volume == doctest::Approx(1.0));

  // The same cube as a binary STL (unshared corners, welded on reading) and as ASCII STL.
  std::string binary(80, ' ');
  const auto put_u32 = [&](std::uint32_t u) {
    for (int i = 0; i < 4; ++i) binary.push_back(char((u >> (8 * i)) & 0xff));
  };
  put_u32(12);
  std::string ascii = "solid cube\n";
  for (const auto& t : cube.triangles) {
    for (int i = 0; i < 3; ++i) put_u32(0);
    ascii += " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const Vec<3>& x = cube.vertices[t[k]];
      for (int i = 0; i < 3; ++i) put_u32(std::bit_cast<std::uint32_t>(float(x[i])));
      ascii += "   vertex " + std::to_string(x[0]) + " " + std::to_string(x[1]) + " " + std::to_string(x[2]) + "\n";
    }
    ascii += "  endloop\n endfacet\n";
    binary += std::string(2, '\0');
  }
  ascii += "endsolid cube\n";
  for (const std::string& file : {write_file("cube_binary.STL", binary), write_file("cube_ascii.stl", ascii)}) {
    const TriangleMesh stl = read_triangle_mesh(file);
    CHECK(stl.vertices.size() == 8);
    REQUIRE(stl.triangles.size() == 12);
    for (std::size_t f = 0; f < 12; ++f)
      for (int k = 0; k < 3; ++k)
        CHECK((stl.vertices[stl.triangles[f][k]] - cube.vertices[cube.triangles[f][k]]).norm() == 0.0);
  }

  const auto error_of = [](const std::string& name, const std::string& text) {
    try {
      read_triangle_mesh(write_file(name, text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(error_of("points.obj", "v 0 0 0\nv 1 0 0\n").find("no triangle") != std::string::npos);
  CHECK(error_of("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").find("bad_index.obj:4") != std::string::npos);
  CHECK(error_of("zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").find(":4") != std::string::npos);
  CHECK(error_of("short_vertex.obj", "v 0 0\n").find("short_vertex.obj:1") != std::string::npos);
  CHECK(error_of("mesh.ply", "ply\n").find("unknown mesh extension") != std::string::npos);
  CHECK(error_of("broken.stl", "not an stl").find("broken.stl") != std::string::npos);
  CHECK_THROWS_WITH_AS(read_triangle_mesh(temp_file("absent.obj")), doctest::Contains("cannot open"), InputError);

  // A closed surface shares every edge between two triangles; the cube without its top does not.
  CHECK_NOTHROW(check_closed(cube, "cube.obj"));
  std::string open_box = kUnitCubeObj;
  open_box.erase(open_box.find("f 5 6 7 8\n"), std::string("f 5 6 7 8\n").size());
  const TriangleMesh open = read_triangle_mesh(write_file("open_box.obj", open_box));
  CHECK_THROWS_WITH_AS(check_closed(open, "open_box.obj"),
                       doctest::Contains("open_box.obj: the mesh is not closed: its edge from (0, 0, 1) to (1, 0, 1) "
                                         "belongs to 1 triangle"),
                       InputError);
}

#ifdef MPM_WITH_OPENVDB

TEST_CASE("mesh level set of the unit cube") {
  const std::string obj = write_file("level_set_cube.obj", kUnitCubeObj);
  const double voxel = 0.05;
  // A band of 12 voxels (0.6 m) reaches the centre, 0.5 m deep.
  const LevelSet cube = LevelSet::from_mesh(obj, voxel, 12.0);
  CHECK(cube.voxel_size() == doctest::Approx(voxel));
  CHECK(std::abs(cube.phi(Vec<3>(0.5, 0.5, 0.5)) + 0.5) < voxel);
  CHECK(std::abs(cube.phi(Vec<3>(1.2, 0.5, 0.5)) - 0.2) < voxel);
  CHECK(std::abs(cube.phi(Vec<3>(0.5, 0.3, 0.5)) + 0.3) < voxel);
  CHECK(cube.inside(Vec<3>(0.9, 0.1, 0.5)));
  CHECK_FALSE(cube.inside(Vec<3>(1.1, 0.5, 0.5)));
  CHECK(cube.phi(Vec<3>(5, 5, 5)) == doctest::Approx(cube.background()));  // beyond the band
  CHECK((cube.normal(Vec<3>(1.1, 0.5, 0.5)) - Vec<3>(1, 0, 0)).norm() < 1e-3);
  CHECK((cube.normal(Vec<3>(0.5, -0.05, 0.4)) - Vec<3>(0, -1, 0)).norm() < 1e-3);
  CHECK(cube.normal(Vec<3>(5, 5, 5)).norm() == 0.0);
  CHECK((cube.bounding_box().lo.array() <= 0.0).all());
  CHECK((cube.bounding_box().hi.array() >= 1.0).all());

  // Round trip through a .vdb file, then the named-grid lookup.
  const std::string vdb = temp_file("cube.vdb");
  cube.write_vdb(vdb);
  const LevelSet loaded = LevelSet::from_vdb(vdb);
  const LevelSet named = LevelSet::from_vdb(vdb, "level_set_cube");
  for (const Vec<3>& x : {Vec<3>(0.5, 0.5, 0.5), Vec<3>(1.13, 0.21, 0.77), Vec<3>(-0.07, 0.5, 0.5)}) {
    CHECK(loaded.phi(x) == cube.phi(x));
    CHECK(named.phi(x) == cube.phi(x));
  }
  CHECK_THROWS_WITH_AS(LevelSet::from_vdb(vdb, "teapot"), doctest::Contains("no grid named 'teapot'"), InputError);
  CHECK_THROWS_WITH_AS(LevelSet::from_vdb(temp_file("absent.vdb")), doctest::Contains("absent.vdb"), InputError);
  // Thrown inside the OpenVDB plugin of a shared build: the one InputError of libmpm_core arrives,
  // with the file and OpenVDB's reason.
  const std::string garbage = write_file("garbage.vdb", "not a vdb");
  const std::string reason = garbage + ": cannot read the OpenVDB file: ";
  CHECK_THROWS_WITH_AS(LevelSet::from_vdb(garbage), doctest::Contains(reason.c_str()), InputError);
  CHECK_THROWS_AS(LevelSet::from_mesh(obj, voxel, 2.0), InputError);
  CHECK_THROWS_WITH_AS(LevelSet::from_mesh(write_file("empty.obj", "v 0 0 0\n"), voxel),
                       doctest::Contains("no triangle"), InputError);

  // The 2D section z = 0.5 is the unit square; its in-plane normal is that of the square.
  const LevelSetShape<2> square(cube, 0.5);
  CHECK(std::abs(square.phi(Vec<2>(0.5, -0.2)) - 0.2) < voxel);
  CHECK((square.normal(Vec<2>(-0.1, 0.5)) - Vec<2>(-1, 0)).norm() < 1e-3);

  // Seeding the interior of the mesh: one particle per sub-cell of the unit cube.
  const auto particles = seed_level_set<3>(LevelSetShape<3>(cube), 0.1, 8, 0.0, 1);
  CHECK(particles.size() == 8000);
  const auto slice = seed_level_set<2>(square, 0.1, 4, 0.0, 1);
  CHECK(slice.size() == 400);
}

TEST_CASE("slotted plate mesh and level-set colliders from a scene") {
  const std::string plate_file = std::string(SEDIMENT_DATA_DIR) + "/meshes/slotted_plate.obj";
  const Config scene = Config::parse(
      "colliders:\n  - {type: level_set, file: " + plate_file + ", voxel_size: 0.005, slice_z: 0.3, contact: slip}\n",
      "scene.yaml");
  const ColliderSet<2> set = parse_colliders<2>(scene, Vec<2>(0, 0), Vec<2>(1, 1), 0.05);
  CHECK(set.uses_level_sets());
  const Collider<2>& plate = set.colliders().front();
  for (const double slit : {0.275, 0.525, 0.775}) {
    CHECK(std::abs(plate.phi(Vec<2>(slit, 0.43), 0.0) - 0.01) < 0.0025);  // half a slit, +- half a voxel
    CHECK(plate.phi(Vec<2>(slit + 0.05, 0.43), 0.0) < 0.0);               // in a bar
  }
  CHECK(std::abs(plate.phi(Vec<2>(0.1, 0.47), 0.0) - 0.01) < 0.0025);  // above the plate
  // No node of a 0.05 m grid is in a slit: the uniform grid sees a solid plate.
  for (int i = 1; i < 20; ++i) CHECK(plate.phi(Vec<2>(0.05 * i, 0.45), 0.0) < 0.0);
  // Outside the slit section (z = 0.05) the plate is solid across.
  const LevelSetShape<2> edge(std::get<LevelSetShape<2>>(plate.shape()).level_set(), 0.05);
  CHECK(edge.phi(Vec<2>(0.275, 0.43)) < 0.0);
}

TEST_CASE("an open mesh is refused as a level set, naming the key and the edge") {
  std::string open_box = kUnitCubeObj;
  open_box.erase(open_box.find("f 5 6 7 8\n"), std::string("f 5 6 7 8\n").size());
  const std::string file = write_file("open_box.obj", open_box);
  const Config scene =
      Config::parse("colliders:\n  - {type: level_set, file: " + file + ", voxel_size: 0.05}\n", "scene.yaml");
  try {
    parse_colliders<3>(scene, Vec<3>::Zero(), Vec<3>::Constant(2.0), 0.1);
    FAIL("an open mesh was accepted");
  } catch (const InputError& e) {
    const std::string message = e.what();
    CHECK(message.find("colliders[0].file") != std::string::npos);
    CHECK(message.find("is not closed") != std::string::npos);
  }
}

#else

TEST_CASE("level sets without OpenVDB fail with the reason") {
  const std::string obj = write_file("cube.obj", kUnitCubeObj);
  CHECK_THROWS_WITH_AS(LevelSet::from_mesh(obj, 0.05), doctest::Contains("-DSEDIMENT_WITH_OPENVDB=ON"), InputError);
  CHECK_THROWS_WITH_AS(LevelSet::from_vdb("plate.vdb"), doctest::Contains("no OpenVDB"), InputError);
  const Config scene = Config::parse("colliders:\n  - {type: level_set, file: " + obj + ", voxel_size: 0.05}\n");
  CHECK_THROWS_WITH_AS(parse_colliders<3>(scene, Vec<3>::Zero(), Vec<3>::Ones(), 0.1), doctest::Contains("no OpenVDB"),
                       InputError);
}

#endif

TEST_CASE("lattice seeding") {
  SUBCASE("an aligned box holds volume / particle volume particles") {
    const double dx = 0.1;
    const auto box2 = seed_box<2>(Vec<2>(0.0, 0.2), Vec<2>(1.0, 0.7), dx, 4, 0.0, 1);
    CHECK(double(box2.size()) == doctest::Approx(0.5 / particle_volume<2>(dx, 4)));
    CHECK(box2.size() == 200);
    const auto box3 = seed_box<3>(Vec<3>(-0.2, 0.0, 0.3), Vec<3>(0.3, 0.4, 0.6), dx, 27, 0.0, 1);
    CHECK(box3.size() == 5 * 4 * 3 * 27);
    CHECK(particle_volume<3>(dx, 27) == doctest::Approx(1e-3 / 27));
    // Sub-cell centres of the global grid.
    for (const Vec<3>& x : box3)
      for (int i = 0; i < 3; ++i) {
        const double s = x[i] / (dx / 3) - 0.5;
        CHECK(std::abs(s - std::round(s)) < 1e-9);
      }
  }
  SUBCASE("adjacent boxes tile without gap or overlap") {
    const auto whole = seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), 0.05, 9, 0.0, 1);
    auto left = seed_box<2>(Vec<2>(0, 0), Vec<2>(0.35, 1), 0.05, 9, 0.0, 1);
    const auto right = seed_box<2>(Vec<2>(0.35, 0), Vec<2>(1, 1), 0.05, 9, 0.0, 1);
    CHECK(left.size() + right.size() == whole.size());
    std::set<std::pair<double, double>> points;
    for (const auto& x : whole) points.insert({x[0], x[1]});
    left.insert(left.end(), right.begin(), right.end());
    for (const auto& x : left) CHECK(points.erase({x[0], x[1]}) == 1);
    CHECK(points.empty());
  }
  SUBCASE("jitter is deterministic, bounded and seed-dependent") {
    const double dx = 0.1, jitter = 0.6, h = dx / 2;
    const auto a = seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), dx, 4, jitter, 42);
    const auto b = seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), dx, 4, jitter, 42);
    const auto c = seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), dx, 4, jitter, 43);
    const auto lattice = seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), dx, 4, 0.0, 42);
    REQUIRE(a.size() == lattice.size());
    REQUIRE(c.size() == lattice.size());
    double largest = 0.0, differs = 0.0;
    for (std::size_t p = 0; p < a.size(); ++p) {
      CHECK((a[p] - b[p]).norm() == 0.0);
      largest = std::max(largest, (a[p] - lattice[p]).cwiseAbs().maxCoeff());
      differs = std::max(differs, (a[p] - c[p]).norm());
    }
    CHECK(largest <= jitter * h / 2);
    CHECK(largest > 0.9 * jitter * h / 2);  // the offsets fill their range
    CHECK(differs > 0.0);
  }
  SUBCASE("a sphere holds about its volume") {
    const double dx = 0.02, r = 0.3;
    const auto ball = seed_sphere<3>(Vec<3>(0.5, 0.5, 0.5), r, dx, 8, 0.5, 3);
    const double volume = double(ball.size()) * particle_volume<3>(dx, 8);
    CHECK(volume == doctest::Approx(4.0 / 3.0 * std::numbers::pi * r * r * r).epsilon(0.01));
    for (const auto& x : ball) CHECK((x - Vec<3>(0.5, 0.5, 0.5)).norm() < r + dx / 2);
  }
  SUBCASE("particles per cell must be a perfect power") {
    CHECK(lattice_points_per_axis<2>(9) == 3);
    CHECK(lattice_points_per_axis<3>(8) == 2);
    CHECK_THROWS_WITH_AS(seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), 0.1, 8, 0.0, 1), doctest::Contains("k^2"), InputError);
    CHECK_THROWS_AS(seed_box<3>(Vec<3>::Zero(), Vec<3>::Ones(), 0.1, 9, 0.0, 1), InputError);
    CHECK_THROWS_AS(seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), 0.1, 0, 0.0, 1), InputError);
    CHECK_THROWS_AS(seed_box<2>(Vec<2>(0, 0), Vec<2>(1, 1), 0.1, 4, 1.0, 1), InputError);
  }
}

TEST_CASE("particle spacing: a lattice is even, a hole shows, the surface layer does not count") {
  // 10 x 10 cells of 4 particles: the inside is the 8 x 8 cells one cell from the edge.
  const double dx = 0.1;
  const Vec<2> origin(-1.0, -1.0);
  std::vector<Vec<2>> x = seed_box<2>(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), dx, 4, 0.0, 1);
  ParticleSpacing even = particle_spacing<2>(x, origin, dx);
  CHECK(even.inside_cells == 64);
  CHECK(even.mean_count == 4.0);
  CHECK(even.count_cv == 0.0);
  CHECK(even.empty_share == 0.0);
  // A cell emptied inside: still inside (the closing fills it), counted empty and sparse.
  std::vector<Vec<2>> holed;
  for (const Vec<2>& p : x)
    if (!(p[0] > 0.5 && p[0] < 0.6 && p[1] > 0.3 && p[1] < 0.4)) holed.push_back(p);
  const ParticleSpacing hole = particle_spacing<2>(holed, origin, dx);
  CHECK(hole.inside_cells == 64);
  CHECK(hole.empty_share == doctest::Approx(1.0 / 64.0));
  CHECK(hole.sparse_share == doctest::Approx(1.0 / 64.0));
  CHECK(hole.mean_count == doctest::Approx(252.0 / 64.0));
  // 3 and 5 particles in two cells: std = sqrt(2 / 64) over a mean of 4.
  std::vector<Vec<2>> moved = x;
  for (Vec<2>& p : moved)
    if (p[0] > 0.5 && p[0] < 0.55 && p[1] > 0.3 && p[1] < 0.35) p[0] += dx;
  const ParticleSpacing uneven = particle_spacing<2>(moved, origin, dx);
  CHECK(uneven.count_cv == doctest::Approx(std::sqrt(2.0 / 64.0) / 4.0));
  CHECK(uneven.empty_share == 0.0);
  // Excluded cells (another phase's) leave the inside: the hole's row drops out, hole and all.
  std::vector<Vec<2>> row;  // one point per cell of row 13 (y in [0.3, 0.4))
  for (int i = 0; i < 10; ++i) row.emplace_back(0.05 + 0.1 * i, 0.35);
  const ParticleSpacing without_row = particle_spacing<2>(holed, origin, dx, row);
  CHECK(without_row.inside_cells == 56);
  CHECK(without_row.empty_share == 0.0);
  // In 3D: 6^3 cells give 4^3 inside.
  const auto cube = seed_box<3>(Vec<3>::Zero(), Vec<3>::Constant(0.6), dx, 8, 0.0, 1);
  CHECK(particle_spacing<3>(cube, Vec<3>::Constant(-1.0), dx).inside_cells == 64);
}

namespace {
//! The gap of body_gap.h over every pair, for comparison.
template <int dim>
double brute_force_gap(const Particles<dim>& P, std::uint16_t a, std::uint16_t b, const std::vector<Mat<dim>>& F) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < P.size(); ++p)
    for (std::size_t q = 0; q < P.size(); ++q)
      if (P.material[p] == a && P.material[q] == b) {
        const Vec<dim> n = (P.x[q] - P.x[p]).normalized();
        best = std::min(best, (P.x[q] - P.x[p]).norm() -
                                  0.5 * std::pow(P.volume0[p], 1.0 / dim) * (F[p].transpose() * n).norm() -
                                  0.5 * std::pow(P.volume0[q], 1.0 / dim) * (F[q].transpose() * n).norm());
      }
  return best;
}

//! Deformation gradients within 30 % of the identity.
template <int dim>
std::vector<Mat<dim>> random_F(std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Mat<dim>> F(n, Mat<dim>::Identity());
  for (Mat<dim>& f : F)
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) f(i, j) += u(rng);
  return F;
}

//! Two sparse random clouds of 30 particles each in the same box, of widths 0.005 and 0.04, so
//! that the closest pair often lies in neighbouring cells of the search and within the reach only
//! through the particles' widths.
template <int dim>
Particles<dim> two_clouds(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 0.3);
  Particles<dim> P;
  for (int i = 0; i < 60; ++i) {
    Vec<dim> x;
    for (int k = 0; k < dim; ++k) x[k] = u(rng);
    P.push_back(x, Vec<dim>::Zero(), 1.0, std::pow(i % 3 == 0 ? 0.04 : 0.005, dim), std::uint16_t(i % 2));
  }
  return P;
}
}  // namespace

TEST_CASE("body gap: lattices side by side, compressed, random clouds against every pair, the reach") {
  // Lattices of particles 0.01 wide, body b starting 0.013 beyond a's last cube: gap 0.013.
  Particles<2> P;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      P.push_back(Vec<2>(0.005 + 0.01 * i, 0.005 + 0.01 * j), Vec<2>::Zero(), 1.0, 1e-4, 0);
      P.push_back(Vec<2>(0.118 + 0.01 * i, 0.005 + 0.01 * j), Vec<2>::Zero(), 1.0, 1e-4, 1);
    }
  CHECK(body_gap(P, 0, 1, 0.05) == doctest::Approx(0.013).epsilon(1e-12));
  CHECK(body_gap(P, 1, 0, 0.05) == doctest::Approx(0.013).epsilon(1e-12));
  CHECK(body_gap(P, 0, 1, 0.01) == 0.01);  // farther apart than the reach
  CHECK(body_gap(P, 0, 2, 0.05) == 0.05);  // no body of material 2
  CHECK_THROWS_AS(body_gap(P, 0, 1, 0.0), InputError);
  CHECK_THROWS_AS(body_gap(P, 1, 1, 0.05), InputError);  // one body against itself
  CHECK_THROWS_AS(body_gap(P, 0, 1, std::numeric_limits<double>::infinity()), InputError);
  {
    Particles<2> broken = P;
    broken.x[7][1] = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_AS(body_gap(broken, 0, 1, 0.05), NumericalError);
    std::vector<Mat<2>> F_broken(broken.size(), Mat<2>::Identity());
    F_broken[4](0, 1) = std::numeric_limits<double>::infinity();
    CHECK_THROWS_AS(body_gap(P, 0, 1, 0.05, &F_broken), NumericalError);
  }
  // A reach far beyond the table's cells: the search clamps to the table.
  CHECK(body_gap(P, 0, 1, 1e300) == doctest::Approx(0.013).epsilon(1e-12));
  // Two particles 0.04 wide with centres 0.08 apart, diagonally in 3D: a gap of 0.04, within a
  // reach of 0.05 through their widths only.
  Particles<3> coarse;
  coarse.push_back(Vec<3>(0.1, 0.1, 0.1), Vec<3>::Zero(), 1.0, std::pow(0.04, 3), 0);
  coarse.push_back(Vec<3>(0.1, 0.1, 0.1) + Vec<3>::Ones() * 0.08 / std::sqrt(3.0), Vec<3>::Zero(), 1.0,
                   std::pow(0.04, 3), 1);
  CHECK(body_gap(coarse, 0, 1, 0.05) == doctest::Approx(0.04).epsilon(1e-12));
  // Lattice a compressed to 0.8 along x (centres 0.008 apart, F = diag(0.8, 1)): its last face at
  // 0.076 + 0.004; b's first at 0.093 - 0.005: a gap of 0.008 with F, 0.007 without.
  Particles<2> pressed;
  std::vector<Mat<2>> F;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      pressed.push_back(Vec<2>(0.004 + 0.008 * i, 0.005 + 0.01 * j), Vec<2>::Zero(), 1.0, 1e-4, 0);
      F.push_back(Vec<2>(0.8, 1.0).asDiagonal());
      pressed.push_back(Vec<2>(0.093 + 0.01 * i, 0.005 + 0.01 * j), Vec<2>::Zero(), 1.0, 1e-4, 1);
      F.push_back(Mat<2>::Identity());
    }
  CHECK(body_gap(pressed, 0, 1, 0.05, &F) == doctest::Approx(0.008).epsilon(1e-12));
  CHECK(body_gap(pressed, 0, 1, 0.05) == doctest::Approx(0.007).epsilon(1e-12));
  // A particle 0.01 wide stretched threefold along x reaches 0.015 towards one 0.04 away: a gap of
  // 0.02, found within a reach of 0.025 only through the stretch.
  Particles<2> stretched;
  stretched.push_back(Vec<2>(0.1, 0.1), Vec<2>::Zero(), 1.0, 1e-4, 0);
  stretched.push_back(Vec<2>(0.14, 0.1), Vec<2>::Zero(), 1.0, 1e-4, 1);
  const std::vector<Mat<2>> stretch{Vec<2>(3.0, 1.0).asDiagonal(), Mat<2>::Identity()};
  CHECK(body_gap(stretched, 0, 1, 0.025, &stretch) == doctest::Approx(0.02).epsilon(1e-12));

  std::mt19937 rng(7);
  const double reach = 0.05;
  int within = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Particles<2> P2 = two_clouds<2>(rng);
    const Particles<3> P3 = two_clouds<3>(rng);
    CAPTURE(trial);
    const std::vector<Mat<2>> F2 = random_F<2>(rng, P2.size());
    const std::vector<Mat<3>> I3(P3.size(), Mat<3>::Identity());
    const double exact2 = brute_force_gap(P2, 0, 1, F2), exact3 = brute_force_gap(P3, 0, 1, I3);
    CHECK(body_gap(P2, 0, 1, reach, &F2) == doctest::Approx(std::min(reach, exact2)).epsilon(1e-12));
    CHECK(body_gap(P3, 1, 0, reach) == doctest::Approx(std::min(reach, exact3)).epsilon(1e-12));
    within += (exact2 < reach) + (exact3 < reach);
  }
  CHECK(within > 100);  // most trials have a pair within reach
}
