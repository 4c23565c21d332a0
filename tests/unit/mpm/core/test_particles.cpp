// Particle channels (core/particles.h): extra channels of every element type stay aligned with
// the particles through every operation that adds, reorders or removes particles; declaring is
// idempotent and refuses a type clash; the memory report, the pipeline fields, particle frames and
// checkpoints see the extra channels through the one list (for_each_channel); and a pipeline
// whose stage reads a channel the particles lack fails when it is assembled.
#include <mpm/core/advance.h>
#include <mpm/core/error.h>
#include <mpm/core/particles.h>
#include <mpm/core/state.h>
#include <mpm/io/checkpoint.h>
#include <mpm/io/particle_output.h>
#include <mpm/solid/material.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>

#include <doctest/doctest.h>
#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <unistd.h>

#include "../hdf5_reading.h"

namespace fs = std::filesystem;
using namespace mpm;

namespace {

constexpr ChannelUse kStored{.output = true, .checkpoint = true};

//! A fresh directory, removed with its content at the end of the test.
class ScratchDir {
public:
  explicit ScratchDir(const std::string& name)
      : path_(fs::temp_directory_path() / ("mpm_test_particles_" + std::to_string(::getpid()) + "_" + name)) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() { fs::remove_all(path_); }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  const fs::path& path() const { return path_; }

private:
  fs::path path_;
};

//! Every channel as (name, its bytes), in the order of for_each_channel: equal means bit-equal.
template <int dim>
std::vector<std::pair<std::string, std::string>> channel_bytes(const Particles<dim>& P) {
  std::vector<std::pair<std::string, std::string>> all;
  P.for_each_channel([&](const ChannelInfo& info, const auto& values) {
    all.emplace_back(info.name,
                     std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(values[0])));
  });
  return all;
}

//! The message of the Error that `run` throws ("" when it throws none).
template <class ErrorType = Error, class Run>
std::string error_of(Run run) {
  try {
    run();
  } catch (const ErrorType& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

//! Declares an extra channel of each type: "age", "anchor", "strain", "tag".
template <int dim>
void declare_extras(Particles<dim>& P) {
  P.add_channel("age", 0.0, kStored);
  P.template add_channel<Vec<dim>>("anchor", Vec<dim>::Zero(), kStored);
  P.template add_channel<Mat<dim>>("strain", Mat<dim>::Identity(), kStored);
  P.template add_channel<std::uint16_t>("tag", 0, kStored);
}

//! n >= 4 particles with random kinematics and random extra channels (declare_extras), with
//! values that only a bit-exact store preserves (-0, a subnormal, a NaN with a payload, the
//! largest uint16).
template <int dim>
Particles<dim> with_extras(std::size_t n, unsigned seed) {
  REQUIRE(n >= 4);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random = [&] { return u(rng); };
  Particles<dim> P;
  declare_extras(P);
  std::vector<double>& age = P.template channel<double>("age");
  std::vector<Vec<dim>>& anchor = P.template channel<Vec<dim>>("anchor");
  std::vector<Mat<dim>>& strain = P.template channel<Mat<dim>>("strain");
  std::vector<std::uint16_t>& tag = P.template channel<std::uint16_t>("tag");
  for (std::size_t p = 0; p < n; ++p) {
    P.push_back(Vec<dim>::NullaryExpr(random), Vec<dim>::NullaryExpr(random), 1.0 + u(rng), 1e-3, 0);
    P.C.back() = Mat<dim>::NullaryExpr(random);
    age.back() = u(rng) / 3.0;
    anchor.back() = Vec<dim>::NullaryExpr(random);
    strain.back() = Mat<dim>::NullaryExpr(random);
    tag.back() = static_cast<std::uint16_t>(rng());
  }
  age[0] = -0.0;
  age[1] = std::numeric_limits<double>::denorm_min();
  const std::uint64_t payload_nan = 0x7ff8'0000'dead'beefULL;
  std::memcpy(&strain[2](1, 0), &payload_nan, sizeof payload_nan);
  tag[3] = 65535;
  return P;
}

}  // namespace

TEST_CASE_TEMPLATE("an extra channel of each type stays aligned through push_back, permute and erase_flagged", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  using V = Vec<dim>;
  using M = Mat<dim>;
  Particles<dim> P;
  std::vector<double>& age = P.add_channel("age", -1.0, kStored);
  std::vector<M>& strain = P.template add_channel<M>("strain", M::Identity(), kStored);
  for (int id = 0; id < 3; ++id) P.push_back(V::Constant(id), V::Zero(), 1.0, 1.0, 0);
  // Declared with particles present: they get the initial value, as every later particle does.
  std::vector<V>& anchor = P.template add_channel<V>("anchor", V::Constant(-2.0), kStored);
  std::vector<std::uint16_t>& tag = P.template add_channel<std::uint16_t>("tag", 7, kStored);
  REQUIRE(anchor.size() == 3);
  CHECK(anchor[2] == V::Constant(-2.0));
  CHECK(tag[0] == 7);
  for (int id = 3; id < 100; ++id) P.push_back(V::Constant(id), V::Zero(), 1.0, 1.0, 0);
  CHECK(age[99] == -1.0);
  CHECK(strain[99] == M::Identity());
  CHECK(anchor[99] == V::Constant(-2.0));
  CHECK(tag[99] == 7);
  CHECK(P.C[99] == M::Zero());
  // The references taken before later channels were added still name the channels.
  CHECK(&age == &P.template channel<double>("age"));
  CHECK(&strain == &P.template channel<M>("strain"));

  // Every channel carries the particle's id, x[0] included.
  for (std::size_t p = 0; p < P.size(); ++p) {
    const double id = static_cast<double>(p);
    age[p] = id + 0.5;
    anchor[p] = V::Constant(2.0 * id);
    strain[p] = M::Constant(id + 0.25);
    tag[p] = static_cast<std::uint16_t>(p);
  }
  const auto holds = [&](std::size_t i, std::uint32_t id) {
    const double d = id;
    return P.x[i][0] == d && age[i] == d + 0.5 && anchor[i] == V::Constant(2.0 * d) &&
           strain[i] == M::Constant(d + 0.25) && tag[i] == id;
  };

  std::vector<std::uint32_t> order(P.size());
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), std::mt19937(5));
  P.permute(order);
  REQUIRE(P.size() == 100);
  for (std::size_t i = 0; i < P.size(); ++i) {
    CAPTURE(i);
    CHECK(holds(i, order[i]));
  }

  std::vector<std::uint8_t> flagged(P.size(), 0);
  std::vector<std::uint32_t> kept;
  for (std::size_t i = 0; i < P.size(); ++i) {
    flagged[i] = order[i] % 3 == 0;
    if (!flagged[i]) kept.push_back(order[i]);
  }
  CHECK(P.erase_flagged(flagged) == 100 - kept.size());
  REQUIRE(P.size() == kept.size());
  P.for_each_channel([&](const ChannelInfo& info, const auto& values) {
    INFO(info.name);
    CHECK(values.size() == P.size());
  });
  for (std::size_t i = 0; i < P.size(); ++i) {
    CAPTURE(i);
    CHECK(holds(i, kept[i]));  // the survivors, in their order
  }

  // A copy is independent of the original, extra channels included.
  Particles<dim> copy = P;
  copy.template channel<double>("age")[0] = -7.0;
  CHECK(age[0] == kept[0] + 0.5);
  CHECK(channel_bytes(Particles<dim>(P)) == channel_bytes(P));

  P.permute({3, 1});  // shorter than size(): keeps the particles listed
  REQUIRE(P.size() == 2);
  CHECK(holds(0, kept[3]));
  CHECK(holds(1, kept[1]));
}

TEST_CASE("reserve gives every channel room without changing a value; reserve_more grows the room geometrically") {
  Particles<3> P;
  std::vector<Mat<3>>& strain = P.add_channel<Mat<3>>("strain", Mat<3>::Identity(), kStored);
  for (int id = 0; id < 10; ++id) P.push_back(Vec<3>::Constant(id), Vec<3>::Zero(), 1.0, 1.0, 0);
  strain[4] = Mat<3>::Constant(4.0);
  const auto before = channel_bytes(P);

  // 18 MiB of strain, so the advice covers whole huge pages (whether the kernel takes it is not
  // observable here: the room and the values are what is checked).
  P.reserve(1 << 18);
  P.for_each_channel([&](const ChannelInfo& info, const auto& values) {
    INFO(info.name);
    CHECK(values.capacity() >= std::size_t{1} << 18);
  });
  CHECK(channel_bytes(P) == before);

  // Seeding body after body: the room at least doubles when it grows, so the copies stay linear.
  Particles<3> Q;
  Q.reserve_more(100);
  CHECK(Q.capacity() == 100);
  Q.resize(100);
  Q.reserve_more(10);
  CHECK(Q.capacity() == 200);
  Q.reserve_more(50);  // fits: nothing moves
  CHECK(Q.capacity() == 200);
  Q.reserve_more(500);
  CHECK(Q.capacity() == 600);
}

TEST_CASE("add_channel is idempotent for the same name and type and refuses a type clash") {
  Particles<2> P;
  P.push_back(Vec<2>::Zero(), Vec<2>::Zero(), 1.0, 1.0, 0);
  std::vector<double>& age = P.add_channel("age", 3.0, kStored);
  age[0] = 4.0;
  // Same name and type: the same channel, its values and first initial value kept.
  CHECK(&P.add_channel("age", 9.0, ChannelUse{}) == &age);
  CHECK(age[0] == 4.0);
  P.push_back(Vec<2>::Zero(), Vec<2>::Zero(), 1.0, 1.0, 0);
  CHECK(age[1] == 3.0);
  CHECK(&P.add_channel<Vec<2>>("x", Vec<2>::Zero(), kStored) == &P.x);  // a kinematic channel too

  const std::string clash = error_of([&] { P.add_channel<Mat<2>>("age", Mat<2>::Zero(), kStored); });
  CHECK(contains(clash, "'age'"));
  CHECK(contains(clash, "double"));
  CHECK(contains(clash, "Mat<2>"));
  CHECK_THROWS_AS(P.add_channel("material", 0.0, kStored), Error);
  CHECK(contains(error_of([&] { P.add_channel("bad/name", 0.0, kStored); }), "'bad/name'"));
  CHECK_THROWS_AS(P.add_channel("", 0.0, kStored), Error);
  CHECK_THROWS_AS(P.add_channel("ok", 0.0, {.output = true, .output_name = "a b"}), Error);
  // Two channels cannot share a dataset of the particle frames.
  CHECK(contains(error_of([&] { P.add_channel("speedup", 0.0, {.output = true, .output_name = "age"}); }), "as 'age'"));
  CHECK_FALSE(P.has_channel("speedup"));

  // Lookups.
  CHECK(P.has_channel("age"));
  CHECK(P.has_channel("x"));
  CHECK_FALSE(P.has_channel("F"));
  CHECK(P.find_channel<double>("age") == &age);
  CHECK(P.find_channel<double>("F") == nullptr);
  CHECK(P.find_channel<std::uint16_t>("age") == nullptr);
  const std::string missing = error_of([&] { P.channel<Mat<2>>("F"); });
  CHECK(contains(missing, "'F'"));
  CHECK(contains(missing, "x, v, C, mass, volume0, material, age"));
  CHECK(contains(error_of([&] { std::as_const(P).channel<Vec<2>>("age"); }), "holds double"));
}

TEST_CASE("the memory report and the pipeline fields list the extra channels after the kinematic ones") {
  Particles<3> P = with_extras<3>(10, 1);
  P.template channel<Mat<3>>("strain").reserve(1000);
  std::vector<std::string> names;
  for (const auto& [name, bytes] : P.memory_per_field()) {
    names.push_back(name);
    if (name == "particle.strain") CHECK(bytes == 1000 * sizeof(Mat<3>));
    if (name == "particle.tag") CHECK(bytes == P.template channel<std::uint16_t>("tag").capacity() * 2);
  }
  const std::vector<std::string> expected{"particle.x",       "particle.v",        "particle.C",   "particle.mass",
                                          "particle.volume0", "particle.material", "particle.age", "particle.anchor",
                                          "particle.strain",  "particle.tag"};
  CHECK(names == expected);
  CHECK(particle_fields(P) == expected);
}

TEST_CASE_TEMPLATE("a checkpoint round trip with an extra channel of each type is bit-exact", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  const ScratchDir dir("round_trip" + std::to_string(dim));
  const Particles<dim> saved = with_extras<dim>(40, 7);
  io::save_checkpoint(dir / "c.h5", saved, {dim, 1, 2, 0.5, 1e-3, "d", "1", 0, {}, {}});

  // Into a set that declares the same channels, seeded with other particles (they are replaced),
  // and one channel more that checkpoints do not keep: it restarts from its initial value.
  Particles<dim> loaded = with_extras<dim>(5, 8);
  std::vector<double>& scratch = loaded.add_channel("scratch", 2.5, ChannelUse{});
  scratch.assign(loaded.size(), -1.0);
  const std::vector<Mat<dim>>* strain = &loaded.template channel<Mat<dim>>("strain");
  io::CheckpointHeader header;
  io::load_checkpoint(dir / "c.h5", header, loaded);
  CHECK(header.frame == 1);
  CHECK(&loaded.template channel<Mat<dim>>("strain") == strain);  // the caller's references stay valid
  REQUIRE(loaded.size() == saved.size());
  CHECK(scratch == std::vector<double>(saved.size(), 2.5));
  auto bytes = channel_bytes(loaded);
  bytes.pop_back();  // scratch
  CHECK(bytes == channel_bytes(saved));
}

TEST_CASE("loading a checkpoint that lacks a declared channel or stores an undeclared one throws InputError") {
  const ScratchDir dir("mismatch");
  const fs::path file = dir / "c.h5";
  io::save_checkpoint(file, with_extras<2>(6, 3), {2, 1, 2, 0.5, 1e-3, "d", "1", 0, {}, {}});
  io::CheckpointHeader header;

  Particles<2> fewer;  // declares none of the extra channels
  const std::string undeclared = error_of<InputError>([&] { io::load_checkpoint(file, header, fewer); });
  CHECK(contains(undeclared, file.string()));
  CHECK(contains(undeclared, "stores the particle channel 'age'"));

  Particles<2> more;
  declare_extras(more);
  more.add_channel("damage", 0.0, {.checkpoint = true});
  const std::string lacking = error_of<InputError>([&] { io::load_checkpoint(file, header, more); });
  CHECK(contains(lacking, file.string()));
  CHECK(contains(lacking, "has no particle channel 'damage'"));

  // The same name with another type is another channel: its dataset has the wrong shape.
  Particles<2> other;
  other.add_channel("age", 0.0, kStored);
  other.add_channel<Mat<2>>("anchor", Mat<2>::Zero(), kStored);
  other.add_channel<Mat<2>>("strain", Mat<2>::Zero(), kStored);
  other.add_channel<std::uint16_t>("tag", 0, kStored);
  const std::string shape = error_of<InputError>([&] { io::load_checkpoint(file, header, other); });
  CHECK(contains(shape, "particle channel 'anchor' has shape 6 x 2, expected 6 x 4"));

  // A phase: the message names it.
  const Particles<2> grains = with_extras<2>(4, 4);
  io::save_checkpoint<2>(dir / "two.h5", {{"fluid", &fewer}, {"sediment", &grains}},
                         {2, 1, 2, 0.5, 1e-3, "d", "1", 0, {}, {}});
  const std::string phase =
      error_of<InputError>([&] { io::load_checkpoint(dir / "two.h5", header, fewer, "sediment"); });
  CHECK(contains(phase, "phase 'sediment' stores the particle channel 'age'"));
  CHECK(fewer.size() == 0);  // untouched by the failed loads
  CHECK(header.frame == 0);
}

TEST_CASE("particle frames write the extra channels marked output, by type") {
  const ScratchDir dir("frames");
  Particles<2> P = with_extras<2>(5, 2);
  P.add_channel("hidden", 1.0, {.checkpoint = true});  // not output
  P.add_channel<Mat<2>>("stretch", Mat<2>::Identity() * 2.0, {.output = true, .output_name = "J_stretch"});
  io::write_particles(dir / io::particle_file_name(0), P, 0.0, 0);
  const std::string h5 = (dir / io::particle_file_name(0)).string();
  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(file >= 0);
  CHECK(dataset_shape(file, "age") == std::vector<hsize_t>{5});
  CHECK(dataset_shape(file, "anchor") == std::vector<hsize_t>{5, 3});  // 2D padded with z = 0
  CHECK(dataset_shape(file, "strain") == std::vector<hsize_t>{5});     // determinant
  CHECK(dataset_shape(file, "tag") == std::vector<hsize_t>{5});
  CHECK(dataset_shape(file, "J_stretch") == std::vector<hsize_t>{5});
  CHECK(H5Lexists(file, "hidden", H5P_DEFAULT) == 0);
  CHECK(H5Lexists(file, "C", H5P_DEFAULT) == 0);
  std::vector<double> J(5);
  const hid_t set = H5Dopen2(file, "J_stretch", H5P_DEFAULT);
  REQUIRE(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, J.data()) >= 0);
  H5Dclose(set);
  H5Fclose(file);
  CHECK(J == std::vector<double>(5, 4.0));

  io::write_time_series_xdmf(dir.path(), {{0, 0.0}});
  std::ifstream in(dir / "particles.xdmf");
  const std::string xdmf{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  for (const char* attribute : {R"(Name="age" AttributeType="Scalar")", R"(Name="anchor" AttributeType="Vector")",
                                R"(Name="tag" AttributeType="Scalar")", ":/J_stretch<"})
    CHECK_MESSAGE(contains(xdmf, attribute), attribute);
  CHECK_FALSE(contains(xdmf, "hidden"));
}

TEST_CASE("a pipeline whose stage reads particle.F is assembled only when the particles carry the solid channels") {
  SceneSettings<2> settings;
  settings.domain_lo = Vec<2>::Zero();
  settings.domain_hi = Vec<2>::Ones();
  settings.dx = 0.1;
  const Config material = Config::parse("{density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3}");
  // Built by hand, without make_solid_scene (which declares the solid channels).
  const std::vector<Material<2>> materials = {parse_material<2>(material)};
  solid::SolidScene<2> scene{
      settings, materials, {}, solid::make_solid_solver<2>("explicit", materials), initial_state(settings), {}};
  CHECK_FALSE(scene.state.particles.has_channel("F"));
  CHECK_THROWS_WITH_AS(solid::make_solid_pipeline(scene),
                       doctest::Contains("reads field 'particle.F' that no earlier stage writes"), InputError);
  CHECK(contains(error_of([&] { solid::elastic_F(scene.state.particles); }), "no channel 'F'"));

  solid::add_solid_channels(scene.state.particles);
  CHECK_NOTHROW(solid::make_solid_pipeline(scene));
  CHECK(solid::make_solid_scene<2>(settings, scene.materials, {}).state.particles.has_channel("plastic"));
}

TEST_CASE("a solid scene of stress-free grains carries no F, stores no elastic energy and falls") {
  const std::string yaml = R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.05}
time: {end: 0.05}
gravity: [0, -9.81]
solver: grains
materials: [{name: sand, density: 2000, youngs_modulus: 1.0e5, poisson_ratio: 0.3}]
bodies: [{shape: box, lo: [0.4, 0.5], hi: [0.6, 0.7], material: sand}]
)";
  solid::SolidScene<2> scene = solid::load_solid_scene<2>(Config::parse(yaml));
  CHECK(scene.solver->name() == "grains");
  CHECK_FALSE(scene.state.particles.has_channel("F"));
  auto pipeline = solid::make_solid_pipeline(scene);
  advance(scene.state, pipeline, 0.05);
  CHECK(solid::elastic_energy(scene.state, scene.materials) == 0.0);
  for (const Vec<2>& v : scene.state.particles.v) CHECK(v[1] == doctest::Approx(-9.81 * 0.05));
  // A stretched body needs F: refused with the key.
  CHECK_THROWS_WITH_AS(solid::load_solid_scene<2>(Config::parse(yaml, "<string>", {"bodies.0.stretch=[0.5, 1]"})),
                       doctest::Contains("stretch"), InputError);
}
