// Output layer (mpm::io): every file is checked by reading it back with the library that
// consumers use (HDF5 C API, libpng, nlohmann::json, strtod), and every value that must survive
// bit-exactly is compared bit by bit.
#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>
#include <mpm/io/cell_output.h>
#include <mpm/io/checkpoint.h>
#include <mpm/io/checksum.h>
#include <mpm/io/diagnostics_csv.h>
#include <mpm/io/particle_output.h>
#include <mpm/io/png_preview.h>
#include <mpm/io/summary_json.h>
#include <mpm/io/surface_output.h>
#include <mpm/solid/solid_channels.h>

#include <doctest/doctest.h>
#include <hdf5.h>
#include <png.h>
#include <Eigen/LU>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "../hdf5_reading.h"

namespace fs = std::filesystem;
using namespace mpm;

namespace {

//! A fresh directory, removed with its content at the end of the test.
class ScratchDir {
public:
  explicit ScratchDir(const std::string& name)
      : path_(fs::temp_directory_path() / ("mpm_test_io_" + std::to_string(::getpid()) + "_" + name)) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() { fs::remove_all(path_); }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  const fs::path& path() const { return path_; }

  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(path_)) names.push_back(entry.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }

private:
  fs::path path_;
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_text(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

//! An empty particle set with the solid channels F and plastic when `solid`: what a scene
//! declares before it loads a checkpoint.
template <int dim>
Particles<dim> declared(bool solid) {
  Particles<dim> p;
  if (solid) solid::add_solid_channels(p);
  return p;
}

//! Random particles, with values that only a bit-exact store preserves: -0, a subnormal, a NaN
//! with a payload, and non-representable decimals; with random solid channels when `deformation`.
template <int dim>
Particles<dim> random_particles(std::size_t n, bool deformation, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles<dim> p = declared<dim>(deformation);
  for (std::size_t i = 0; i < n; ++i)
    p.push_back(Vec<dim>::NullaryExpr([&] { return u(rng); }), Vec<dim>::NullaryExpr([&] { return u(rng); }),
                1.0 + u(rng), 1e-3 * (1.5 + u(rng)), static_cast<std::uint16_t>(rng() % 7));
  for (auto& C : p.C) C = Mat<dim>::NullaryExpr([&] { return u(rng); });
  if (deformation) {
    for (auto& F : solid::elastic_F(p)) F = Mat<dim>::Identity() + 0.1 * Mat<dim>::NullaryExpr([&] { return u(rng); });
    for (auto& plastic : solid::plastic_state(p)) plastic = 0.01 * u(rng);
  }
  p.v[0][0] = -0.0;
  p.mass[1] = std::numeric_limits<double>::denorm_min();
  std::uint64_t payload_nan = 0x7ff8'0000'dead'beefULL;
  std::memcpy(&p.C[2](0, 0), &payload_nan, sizeof payload_nan);
  p.material[3] = 65535;
  return p;
}

// ---------------------------------------------------------------- PNG reading (libpng)

struct Picture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  std::array<int, 3> at(int i, int j) const {
    const std::size_t k = 3 * (std::size_t(j) * width + i);
    return {rgb[k], rgb[k + 1], rgb[k + 2]};
  }
};

Picture read_png(const fs::path& path) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  REQUIRE(png_image_begin_read_from_file(&image, path.c_str()));
  image.format = PNG_FORMAT_RGB;
  Picture picture{int(image.width), int(image.height), std::vector<std::uint8_t>(PNG_IMAGE_SIZE(image))};
  REQUIRE(png_image_finish_read(&image, nullptr, picture.rgb.data(), 0, nullptr));
  return picture;
}

}  // namespace

TEST_CASE("the temporary files of a killed process are removed, those of live ones kept") {
  const ScratchDir dir("stale");
  // A child that has exited and been reaped: its PID names no process any more.
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  const std::string dead = std::to_string(child), live = std::to_string(::getpid()),
                    parent = std::to_string(::getppid());
  write_text(dir / ("frame_0001.h5.tmp-" + dead), "half");
  write_text(dir / ("summary.json.tmp-" + dead), "half");
  write_text(dir / ("frame_0002.h5.tmp-" + live), "being written");
  write_text(dir / ("preview_0001.png.tmp-" + parent), "being written");
  write_text(dir / "notes.tmp-abc", "not ours");
  write_text(dir / "frame_0001.h5", "complete");
  CHECK(io::remove_stale_temporaries(dir.path()) == 2);
  CHECK(dir.entries() == std::vector<std::string>{"frame_0001.h5", "frame_0002.h5.tmp-" + live, "notes.tmp-abc",
                                                  "preview_0001.png.tmp-" + parent});
  CHECK(io::remove_stale_temporaries(dir / "missing") == 0);
}

TEST_CASE("the leaves of an adaptive grid are written as cells with their level, and a time series") {
  ScratchDir dir("cells");
  adaptive::CellTree<2> tree(Vec<2>::Zero(), IVec<2>(2, 1), 1.0, 3);
  tree.refine(0, IVec<2>(1, 0));
  tree.refine(1, IVec<2>(3, 1));  // leaves: 1 of level 0, 3 of level 1, 4 of level 2
  io::write_cells(dir.path() / "cells_0000.h5", tree, 0.5, 0);
  io::write_cells_time_series<2>(dir.path(), {{0, 0.5}});
  const hid_t file = H5Fopen((dir.path() / "cells_0000.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(file >= 0);
  const auto level = read_dataset<std::int32_t>(file, "level", H5T_NATIVE_INT32);
  CHECK(level == std::vector<std::int32_t>{0, 1, 1, 1, 2, 2, 2, 2});
  CHECK(dataset_shape(file, "cells") == std::vector<hsize_t>{8, 4});
  const auto points = read_dataset<double>(file, "points", H5T_NATIVE_DOUBLE);
  // The area of the quadrilaterals (shoelace) adds up to the domain's: the leaves tile it.
  double area = 0.0;
  for (std::size_t c = 0; c < 8; ++c)
    for (int k = 0; k < 4; ++k) {
      const double* a = &points[(4 * c + k) * 3];
      const double* b = &points[(4 * c + (k + 1) % 4) * 3];
      area += 0.5 * (a[0] * b[1] - b[0] * a[1]);
    }
  CHECK(area == doctest::Approx(2.0));
  H5Fclose(file);
  const std::string series = read_text(dir.path() / "cells.xdmf");
  CHECK(series.find("TopologyType=\"Quadrilateral\" NumberOfElements=\"8\"") != std::string::npos);
  CHECK(series.find("cells_0000.h5:/level") != std::string::npos);
}

TEST_CASE("write_surface stores the domain corners and outward faces, and the series names them") {
  ScratchDir dir("surface");
  domains::ParticleDomains<2> d;  // a 2 x 1 block of particles with unit cells
  domains::add_body<2>(d, 0, {Vec<2>(0.5, 0.5), Vec<2>(1.5, 0.5)}, 1.0, Vec<2>(1.0, 1.0));
  domains::index_sharing(d);
  io::write_surface(dir.path() / "surface_0003.h5", d, 0.25, 3);
  io::write_surface_time_series<2>(dir.path(), {{3, 0.25}});
  const hid_t file = H5Fopen((dir.path() / "surface_0003.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(file >= 0);
  CHECK(dataset_shape(file, "points") == std::vector<hsize_t>{6, 3});
  CHECK(dataset_shape(file, "faces") == std::vector<hsize_t>{6, 2});
  const auto points = read_dataset<double>(file, "points", H5T_NATIVE_DOUBLE);
  const auto faces = read_dataset<std::int32_t>(file, "faces", H5T_NATIVE_INT32);
  double area = 0.0;  // shoelace over the edges: counter-clockwise, the block's area 2
  for (std::size_t e = 0; e < 6; ++e) {
    const double* a = &points[faces[2 * e] * 3];
    const double* b = &points[faces[2 * e + 1] * 3];
    area += 0.5 * (a[0] * b[1] - b[0] * a[1]);
  }
  CHECK(area == doctest::Approx(2.0));
  H5Fclose(file);
  const std::string series = read_text(dir.path() / "surface.xdmf");
  CHECK(series.find("TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"6\"") != std::string::npos);
  CHECK(series.find("surface_0003.h5:/points") != std::string::npos);
}

TEST_CASE("write_embedded_mesh stores the embedded vertices where the corners put them") {
  ScratchDir dir("mesh");
  domains::ParticleDomains<3> d;  // one unit domain about (0.5, 0.5, 0.5), a triangle in it
  domains::add_body<3>(d, 0, {Vec<3>(0.5, 0.5, 0.5)}, 1.0, Vec<3>::Ones());
  domains::embed_mesh<3>(d, 0, {Vec<3>(0.5, 0.5, 0.5)}, 1.0,
                         {Vec<3>(0.25, 0.5, 0.5), Vec<3>(0.75, 0.5, 0.5), Vec<3>(0.5, 0.75, 0.5)}, {{0, 1, 2}});
  domains::index_sharing(d);
  for (Vec<3>& x : d.x) x *= 2.0;  // the domain doubled about the origin: the vertices follow
  io::write_embedded_mesh(dir.path() / "mesh_0002.h5", d, 0.5, 2);
  io::write_embedded_mesh_time_series(dir.path(), {{2, 0.5}});
  const hid_t file = H5Fopen((dir.path() / "mesh_0002.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(file >= 0);
  CHECK(dataset_shape(file, "points") == std::vector<hsize_t>{3, 3});
  CHECK(dataset_shape(file, "triangles") == std::vector<hsize_t>{1, 3});
  const auto points = read_dataset<double>(file, "points", H5T_NATIVE_DOUBLE);
  CHECK(points == std::vector<double>{0.5, 1.0, 1.0, 1.5, 1.0, 1.0, 1.0, 1.5, 1.0});
  CHECK(read_dataset<std::int32_t>(file, "triangles", H5T_NATIVE_INT32) == std::vector<std::int32_t>{0, 1, 2});
  H5Fclose(file);
  const std::string series = read_text(dir.path() / "mesh.xdmf");
  CHECK(series.find("TopologyType=\"Triangle\" NumberOfElements=\"1\"") != std::string::npos);
  CHECK(series.find("mesh_0002.h5:/triangles") != std::string::npos);
}

TEST_CASE("write_file_atomically replaces the file and leaves no temporary file") {
  const ScratchDir dir("atomic");
  io::write_file_atomically(dir / "a.txt", "first");
  io::write_file_atomically(dir / "a.txt", std::string("second\0binary", 13));
  CHECK(read_text(dir / "a.txt") == std::string("second\0binary", 13));
  CHECK(dir.entries() == std::vector<std::string>{"a.txt"});

  SUBCASE("a write into a missing folder throws IoError naming the path") {
    write_text(dir / "file", "not a folder");
    const fs::path target = dir / "file" / "out.txt";
    try {
      io::write_file_atomically(target, "x");
      FAIL("no IoError");
    } catch (const IoError& e) {
      CHECK(std::string(e.what()).find(target.string()) != std::string::npos);
    }
    CHECK(dir.entries() == std::vector<std::string>{"a.txt", "file"});
  }
  SUBCASE("a failed rename removes the written temporary file") {
    fs::create_directory(dir / "occupied");
    fs::path inner = dir / "occupied" / "x";
    write_text(inner, "keeps the folder non-empty");
    CHECK_THROWS_AS(io::write_file_atomically(dir / "occupied", "content"), IoError);
    CHECK(dir.entries() == std::vector<std::string>{"a.txt", "occupied"});
    CHECK(read_text(inner) == "keeps the folder non-empty");
  }
  SUBCASE("an AtomicFile destroyed uncommitted removes its temporary file") {
    {
      io::AtomicFile file(dir / "b.txt");
      write_text(file.temp_path(), "partial");
      CHECK(file.temp_path().parent_path() == dir.path());
      CHECK(file.temp_path().filename() == "b.txt.tmp-" + std::to_string(::getpid()));
    }
    CHECK(dir.entries() == std::vector<std::string>{"a.txt"});
  }
}

TEST_CASE("every writer throws IoError naming its target and leaves no file when it cannot write") {
  const ScratchDir dir("unwritable");
  write_text(dir / "file", "a file where a folder is expected");
  const fs::path folder = dir / "file";
  const Particles<2> p = random_particles<2>(5, true, 9);
  const auto throws_naming = [](auto write, const fs::path& target) {
    try {
      write();
    } catch (const IoError& e) {
      return std::string(e.what()).find(target.string()) != std::string::npos;
    }
    return false;
  };
  CHECK(throws_naming([&] { io::write_particles(folder / "particles_0000.h5", p, 0.0, 0); },
                      folder / "particles_0000.h5"));
  CHECK(throws_naming(
      [&] {
        io::save_checkpoint(folder / "c.h5", p, {2, 0, 0, 0.0, 0.0, "", "1", 0, {}, {}});
      },
      folder / "c.h5"));
  CHECK(throws_naming([&] { io::write_png_preview(folder / "p.png", p, {}); }, folder / "p.png"));
  CHECK(throws_naming([&] { io::write_summary(folder / "s.json", {}, {}, {}); }, folder / "s.json"));
  CHECK(throws_naming([&] { io::DiagnosticsCsv().open(folder / "d.csv", {"frame"}); }, folder / "d.csv"));
  CHECK(dir.entries() == std::vector<std::string>{"file"});
}

TEST_CASE_TEMPLATE("checkpoint round trip is bit-identical", Dim, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int dim = Dim::value;
  const ScratchDir dir("checkpoint" + std::to_string(dim));
  for (const bool deformation : {false, true}) {
    CAPTURE(deformation);
    const Particles<dim> p = random_particles<dim>(50, deformation, 7);
    const io::CheckpointHeader saved{dim,
                                     12,
                                     3456789012345,
                                     0.1 + 0.2,
                                     1.0 / 3.0,
                                     "sha256:abc",
                                     "123456789",
                                     3456789012000,
                                     {{"obstacles.0.file", "/data/pipe.obj", "00ff00ff00ff00ff"}},
                                     {{"3.pressure/p", {0.1, -2.5e-300, 7.0}}, {"empty", {}}}};
    io::save_checkpoint(dir / "c.h5", p, saved);
    io::CheckpointHeader loaded;
    // Particles seeded before the load are replaced.
    Particles<dim> q = random_particles<dim>(3, deformation, 11);
    io::load_checkpoint(dir / "c.h5", loaded, q);

    CHECK(same_bits(p.x, q.x));
    CHECK(same_bits(p.v, q.v));
    CHECK(same_bits(p.C, q.C));
    CHECK(same_bits(p.mass, q.mass));
    CHECK(same_bits(p.volume0, q.volume0));
    CHECK(same_bits(p.material, q.material));
    if (deformation) {
      CHECK(same_bits(solid::elastic_F(p), solid::elastic_F(q)));
      CHECK(same_bits(solid::plastic_state(p), solid::plastic_state(q)));
    }
    CHECK(q.has_channel("F") == deformation);
    CHECK(loaded.dim == dim);
    CHECK(loaded.frame == saved.frame);
    CHECK(loaded.step == saved.step);
    CHECK(loaded.time == saved.time);
    CHECK(loaded.dt_previous == saved.dt_previous);
    CHECK(loaded.scene_digest == saved.scene_digest);
    CHECK(loaded.stage_data == saved.stage_data);
    CHECK(loaded.run_id == saved.run_id);
    CHECK(loaded.frame_step == saved.frame_step);
    CHECK(loaded.inputs == saved.inputs);
    CHECK(dir.entries() == std::vector<std::string>{"c.h5"});
  }
  SUBCASE("several phases in one file, each in its group") {
    const Particles<dim> fluid = random_particles<dim>(30, false, 8), grains = random_particles<dim>(20, true, 9);
    io::save_checkpoint<dim>(dir / "two.h5", {{"fluid", &fluid}, {"sediment", &grains}},
                             {dim, 1, 2, 0.5, 1e-3, "d", "1", 0, {}, {}});
    io::CheckpointHeader header;
    Particles<dim> f = declared<dim>(false), g = declared<dim>(true);
    io::load_checkpoint(dir / "two.h5", header, f, "fluid");
    io::load_checkpoint(dir / "two.h5", header, g, "sediment");
    CHECK(same_bits(f.x, fluid.x));
    CHECK(same_bits(f.C, fluid.C));
    CHECK_FALSE(f.has_channel("F"));
    CHECK(same_bits(g.v, grains.v));
    CHECK(same_bits(solid::elastic_F(g), solid::elastic_F(grains)));
    // The grains' F in particles that do not declare it, and the reverse.
    Particles<dim> plain;
    CHECK_THROWS_WITH_AS(io::load_checkpoint(dir / "two.h5", header, plain, "sediment"),
                         doctest::Contains("phase 'sediment' stores the particle channel 'F'"), InputError);
    CHECK_THROWS_WITH_AS(io::load_checkpoint(dir / "two.h5", header, g, "fluid"),
                         doctest::Contains("phase 'fluid' has no particle channel 'F'"), InputError);
    CHECK_THROWS_WITH_AS(io::load_checkpoint(dir / "two.h5", header, f, "air"),
                         doctest::Contains("no particle phase 'air'"), InputError);
    CHECK_THROWS_AS(io::load_checkpoint(dir / "two.h5", header, f), InputError);
  }
  SUBCASE("an empty particle set keeps its channels") {
    for (const bool deformation : {false, true}) {
      io::save_checkpoint(dir / "empty.h5", declared<dim>(deformation), {dim, 0, 0, 0.0, 0.0, "", "1", 0, {}, {}});
      io::CheckpointHeader header;
      Particles<dim> q = random_particles<dim>(4, deformation, 12);
      io::load_checkpoint(dir / "empty.h5", header, q);
      CHECK(q.size() == 0);
      CHECK(header.scene_digest.empty());
      Particles<dim> other = declared<dim>(!deformation);
      CHECK_THROWS_AS(io::load_checkpoint(dir / "empty.h5", header, other), InputError);
    }
  }
}

TEST_CASE("loading a wrong, missing or corrupt checkpoint throws naming the file") {
  const ScratchDir dir("bad_checkpoint");
  const auto names_file = [](const Error& e, const fs::path& file) {
    return std::string(e.what()).find(file.string()) != std::string::npos;
  };
  io::CheckpointHeader header;
  io::save_checkpoint(dir / "3d.h5", random_particles<3>(10, true, 1), {3, 1, 2, 0.5, 1e-3, "d", "1", 0, {}, {}});
  Particles<2> in_2d = declared<2>(true);
  Particles<3> in_3d = declared<3>(true);

  try {
    io::load_checkpoint(dir / "3d.h5", header, in_2d);
    FAIL("no InputError for the wrong dimension");
  } catch (const InputError& e) {
    CHECK(names_file(e, dir / "3d.h5"));
    CHECK(std::string(e.what()).find("3D") != std::string::npos);
  }
  try {
    io::load_checkpoint(dir / "missing.h5", header, in_3d);
    FAIL("no IoError for a missing file");
  } catch (const IoError& e) {
    CHECK(names_file(e, dir / "missing.h5"));
  }
  write_text(dir / "garbage.h5", "this is not an HDF5 file");
  CHECK_THROWS_AS(io::load_checkpoint(dir / "garbage.h5", header, in_3d), IoError);

  const std::string whole = read_text(dir / "3d.h5");
  write_text(dir / "truncated.h5", whole.substr(0, whole.size() / 2));
  try {
    io::load_checkpoint(dir / "truncated.h5", header, in_3d);
    FAIL("no IoError for a truncated file");
  } catch (const IoError& e) {
    CHECK(names_file(e, dir / "truncated.h5"));
  }
  CHECK(header.frame == 0);  // untouched by the failed loads
  CHECK(in_3d.size() == 0);

  io::write_particles(dir / "particles_0000.h5", random_particles<3>(4, false, 2), 0.0, 0);
  CHECK_THROWS_AS(io::load_checkpoint(dir / "particles_0000.h5", header, in_3d), InputError);
}

TEST_CASE("a checkpoint may lack a derived channel, which loads as unknown, and no other") {
  const ScratchDir dir("derived_checkpoint");
  const Particles<3> saved = random_particles<3>(10, true, 3);  // written before the stress cache
  io::save_checkpoint(dir / "old.h5", saved, {3, 1, 2, 0.5, 1e-3, "d", "1", 0, {}, {}});
  io::CheckpointHeader header;
  Particles<3> with_cache = declared<3>(true);
  solid::add_stress_cache(with_cache);
  io::load_checkpoint(dir / "old.h5", header, with_cache);
  REQUIRE(with_cache.size() == saved.size());
  CHECK(same_bits(solid::elastic_F(with_cache), solid::elastic_F(saved)));
  for (const Mat<3>& tau : *solid::stress_cache(with_cache)) CHECK_FALSE(solid::known_stress(tau));

  Particles<3> with_damage = declared<3>(true);
  with_damage.add_channel<double>("damage", 0.0, {.checkpoint = true});
  CHECK_THROWS_AS(io::load_checkpoint(dir / "old.h5", header, with_damage), InputError);
}

TEST_CASE("a checkpoint changed after it was written is refused by its checksums") {
  const ScratchDir dir("changed_checkpoint");
  const Particles<3> p = random_particles<3>(10, true, 1);
  io::save_checkpoint(dir / "c.h5", p, {3, 1, 2, 0.5, 1e-3, "d", "1", 0, {}, {{"stage/x", {4.25}}}});
  const std::string whole = read_text(dir / "c.h5");
  // The bytes of a double, found in the file and replaced in place: the file stays a valid HDF5
  // file with the same datasets, only one value differs (as an edit with an HDF5 tool would).
  const auto changed = [&](double from, double to) {
    std::string bytes(sizeof(double), '\0'), replacement(sizeof(double), '\0');
    std::memcpy(bytes.data(), &from, sizeof(double));
    std::memcpy(replacement.data(), &to, sizeof(double));
    const std::size_t at = whole.find(bytes);
    REQUIRE(at != std::string::npos);
    REQUIRE(whole.find(bytes, at + 1) == std::string::npos);
    std::string text = whole;
    text.replace(at, sizeof(double), replacement);
    return text;
  };
  io::CheckpointHeader header;
  Particles<3> into = declared<3>(true);
  io::load_checkpoint(dir / "c.h5", header, into);  // the original loads
  write_text(dir / "mass.h5", changed(p.mass[3], 1000 * p.mass[3]));
  CHECK_THROWS_WITH_AS(io::load_checkpoint(dir / "mass.h5", header, into),
                       doctest::Contains("checksum of its particle data"), IoError);
  write_text(dir / "stage.h5", changed(4.25, 4.5));
  CHECK_THROWS_WITH_AS(io::load_checkpoint(dir / "stage.h5", header, into), doctest::Contains("header checksum"),
                       IoError);
  CHECK(header.stage_data.front().second == std::vector<double>{4.25});  // untouched by the refused loads
}

TEST_CASE("the content checksum sees one changed bit, the order of pieces and their lengths") {
  const auto of = [](std::initializer_list<std::string_view> pieces) {
    io::Checksum sum;
    for (const auto piece : pieces) sum.add(piece);
    return sum.value();
  };
  CHECK(of({"abcdefghij"}) == of({"abcdefghij"}));
  CHECK(of({"abcdefghij"}) != of({"abcdefghik"}));
  CHECK(of({"ab", "c"}) != of({"a", "bc"}));
  CHECK(of({""}) != of({"", ""}));
  std::vector<double> values(1000, 1.0);
  io::Checksum a, b;
  a.add(values.data(), values.size() * sizeof(double));
  values[517] = std::nextafter(1.0, 2.0);
  b.add(values.data(), values.size() * sizeof(double));
  CHECK(a.value() != b.value());
  CHECK(a.hex().size() == 16);
}

TEST_CASE("particle HDF5 file holds the documented datasets") {
  const ScratchDir dir("particles");
  const Particles<2> p = random_particles<2>(20, true, 3);
  const fs::path h5 = dir / io::particle_file_name(7);
  CHECK(h5.filename() == "particles_0007.h5");
  io::write_particles(h5, p, 0.125, 7);
  CHECK(dir.entries() == std::vector<std::string>{"particles_0007.h5", "particles_0007.xdmf"});

  const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(file >= 0);
  const hsize_t n = p.size();
  CHECK(dataset_shape(file, "position") == std::vector<hsize_t>{n, 3});
  CHECK(dataset_shape(file, "velocity") == std::vector<hsize_t>{n, 3});
  const auto position = read_dataset<double>(file, "position", H5T_NATIVE_DOUBLE);
  const auto velocity = read_dataset<double>(file, "velocity", H5T_NATIVE_DOUBLE);
  const auto mass = read_dataset<double>(file, "mass", H5T_NATIVE_DOUBLE);
  const auto volume0 = read_dataset<double>(file, "volume0", H5T_NATIVE_DOUBLE);
  const auto material = read_dataset<int>(file, "material", H5T_NATIVE_INT);
  const auto speed = read_dataset<double>(file, "speed", H5T_NATIVE_DOUBLE);
  const auto J = read_dataset<double>(file, "J", H5T_NATIVE_DOUBLE);
  const auto plastic = read_dataset<double>(file, "plastic", H5T_NATIVE_DOUBLE);
  for (std::size_t i = 0; i < p.size(); ++i) {
    CAPTURE(i);
    CHECK(position[3 * i] == p.x[i][0]);
    CHECK(position[3 * i + 1] == p.x[i][1]);
    CHECK(position[3 * i + 2] == 0.0);
    CHECK(velocity[3 * i] == p.v[i][0]);
    CHECK(velocity[3 * i + 1] == p.v[i][1]);
    CHECK(velocity[3 * i + 2] == 0.0);
    CHECK(speed[i] == p.v[i].norm());
    CHECK(J[i] == solid::elastic_F(p)[i].determinant());
    CHECK(material[i] == p.material[i]);
  }
  CHECK(same_bits(mass, p.mass));
  CHECK(same_bits(volume0, p.volume0));
  CHECK(same_bits(plastic, solid::plastic_state(p)));
  CHECK(read_attribute<double>(file, "time", H5T_NATIVE_DOUBLE) == 0.125);
  CHECK(read_attribute<int>(file, "frame", H5T_NATIVE_INT) == 7);
  CHECK(read_attribute<int>(file, "dim", H5T_NATIVE_INT) == 2);
  H5Fclose(file);

  const fs::path h5_3d = dir / io::particle_file_name(8);
  io::write_particles(h5_3d, random_particles<3>(5, false, 4), 0.25, 8);
  const hid_t file3 = H5Fopen(h5_3d.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  CHECK(H5Lexists(file3, "J", H5P_DEFAULT) == 0);
  CHECK(H5Lexists(file3, "plastic", H5P_DEFAULT) == 0);
  CHECK(read_attribute<int>(file3, "dim", H5T_NATIVE_INT) == 3);
  H5Fclose(file3);
}

namespace {

//! The texts between each `open` and the `close` that follows it, in order.
std::vector<std::string> all_between(const std::string& text, const std::string& open, const std::string& close) {
  std::vector<std::string> found;
  for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at)) {
    at += open.size();
    const std::size_t end = text.find(close, at);
    REQUIRE(end != std::string::npos);
    found.push_back(text.substr(at, end - at));
    at = end;
  }
  return found;
}

//! Checks that every DataItem of an XDMF file names an existing HDF5 dataset of the stated
//! dimensions; returns how many there are.
int check_data_items(const fs::path& xdmf) {
  int count = 0;
  for (const std::string& item : all_between(read_text(xdmf), "<DataItem ", "</DataItem>")) {
    CAPTURE(item);
    CHECK(item.find(R"(Format="HDF")") != std::string::npos);
    const std::string dimensions = all_between(item, "Dimensions=\"", "\"").at(0);
    const std::string reference = item.substr(item.find('>') + 1);  // "file.h5:/dataset"
    const std::size_t colon = reference.find(':');
    const std::string h5 = (xdmf.parent_path() / reference.substr(0, colon)).string();
    const hid_t file = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    REQUIRE(file >= 0);
    std::string dims;
    for (const hsize_t d : dataset_shape(file, reference.substr(colon + 1)))
      dims += (dims.empty() ? "" : " ") + std::to_string(d);
    H5Fclose(file);
    CHECK(dims == dimensions);
    ++count;
  }
  return count;
}

}  // namespace

TEST_CASE("XDMF files reference existing datasets with their dimensions") {
  const ScratchDir dir("xdmf");
  io::write_particles(dir / io::particle_file_name(0), random_particles<2>(6, false, 5), 0.0, 0);
  io::write_particles(dir / io::particle_file_name(1), random_particles<2>(9, true, 6), 0.1, 1);
  io::write_particles(dir / io::particle_file_name(2), random_particles<2>(9, true, 7), 0.2, 2);

  const std::string frame1 = read_text(dir / "particles_0001.xdmf");
  CHECK(frame1.find(R"(<Topology TopologyType="Polyvertex" NumberOfElements="9" NodesPerElement="1"/>)") !=
        std::string::npos);
  CHECK(frame1.find(R"(<Geometry GeometryType="XYZ">)") != std::string::npos);
  CHECK(frame1.find(">particles_0001.h5:/position</DataItem>") != std::string::npos);
  CHECK(check_data_items(dir / "particles_0000.xdmf") == 6);  // position + 5 attributes
  CHECK(check_data_items(dir / "particles_0001.xdmf") == 8);  // ... + J, plastic

  io::write_time_series_xdmf(dir.path(), {{0, 0.0}, {1, 0.1}, {2, 0.2}});
  const std::string series = read_text(dir / "particles.xdmf");
  CHECK(series.find(R"(CollectionType="Temporal")") != std::string::npos);
  CHECK(check_data_items(dir / "particles.xdmf") == 6 + 8 + 8);
  std::vector<double> times;
  for (const std::string& value : all_between(series, "<Time Value=\"", "\""))
    times.push_back(std::strtod(value.c_str(), nullptr));
  CHECK(times == std::vector<double>{0.0, 0.1, 0.2});

  CHECK_THROWS_AS(io::write_time_series_xdmf(dir.path(), {{3, 0.3}}), IoError);
}

TEST_CASE("PNG preview: size, colours, painter's order and NaN") {
  const ScratchDir dir("png");
  io::PreviewOptions options;
  options.domain_lo = {0.0, 0.0, 0.0};
  options.domain_hi = {2.0, 1.0, 1.0};
  options.width_px = 200;
  options.point_radius_px = 3.0;
  options.color_range = std::array<double, 2>{0.0, 1.0};

  Particles<2> p;
  p.push_back({0.5, 0.5}, {1.0, 0.0}, 1.0, 1.0, 0);            // speed 1: top of the map
  p.push_back({1.5, 0.25}, {0.0, 0.0}, 1.0, 1.0, 0);           // speed 0: bottom
  p.push_back({1.0, 0.75}, {std::nan(""), 0.0}, 1.0, 1.0, 0);  // NaN speed: magenta
  p.push_back({std::nan(""), 0.5}, {0.0, 0.0}, 1.0, 1.0, 0);   // NaN position: skipped
  p.push_back({1e300, -1e300}, {0.0, 0.0}, 1.0, 1.0, 0);       // far outside: skipped
  io::write_png_preview(dir / "p.png", p, options);

  const std::string bytes = read_text(dir / "p.png");
  REQUIRE(bytes.size() > 24);
  CHECK(bytes.substr(0, 8) == "\x89PNG\r\n\x1a\n");
  CHECK(bytes.substr(12, 4) == "IHDR");
  const auto big_endian = [&](std::size_t at) {
    return (std::uint32_t(std::uint8_t(bytes[at])) << 24) | (std::uint32_t(std::uint8_t(bytes[at + 1])) << 16) |
           (std::uint32_t(std::uint8_t(bytes[at + 2])) << 8) | std::uint32_t(std::uint8_t(bytes[at + 3]));
  };
  CHECK(big_endian(16) == 200);
  CHECK(big_endian(20) == 100);

  const Picture picture = read_png(dir / "p.png");
  CHECK(picture.at(50, 50) == std::array<int, 3>{253, 231, 37});   // (0.5, 0.5): x right, y up
  CHECK(picture.at(150, 75) == std::array<int, 3>{68, 1, 84});     // (1.5, 0.25)
  CHECK(picture.at(100, 25) == std::array<int, 3>{255, 0, 255});   // (1.0, 0.75)
  CHECK(picture.at(20, 90) == std::array<int, 3>{255, 255, 255});  // background
  CHECK(picture.at(0, 0) == std::array<int, 3>{64, 64, 64});       // frame
  CHECK(picture.at(199, 99) == std::array<int, 3>{64, 64, 64});

  SUBCASE("in 3D the particle with the larger z is drawn on top") {
    Particles<3> q;
    q.push_back({0.5, 0.5, 0.9}, {0.0, 0.0, 0.0}, 1.0, 1.0, 0);  // near, speed 0, listed first
    q.push_back({0.5, 0.5, 0.1}, {0.0, 1.0, 0.0}, 1.0, 1.0, 0);  // far, speed 1
    io::write_png_preview(dir / "q.png", q, options);
    CHECK(read_png(dir / "q.png").at(50, 50) == std::array<int, 3>{68, 1, 84});
  }
  SUBCASE("invalid options throw InputError") {
    options.color_by = "temperature";
    CHECK_THROWS_AS(io::write_png_preview(dir / "r.png", p, options), InputError);
    options.color_by = "J";  // p carries no deformation
    CHECK_THROWS_AS(io::write_png_preview(dir / "r.png", p, options), InputError);
    options.color_by = "speed";
    options.width_px = 0;
    CHECK_THROWS_AS(io::write_png_preview(dir / "r.png", p, options), InputError);
    CHECK(!fs::exists(dir / "r.png"));
  }
}

TEST_CASE("diagnostics CSV: full precision, fixed row length, restart truncation") {
  const ScratchDir dir("csv");
  const std::vector<std::string> columns{"frame", "time", "energy"};
  const auto row = [](int frame) { return std::vector<double>{double(frame), 0.1 * frame, 1.0 / (3.0 + frame)}; };
  io::DiagnosticsCsv csv;
  csv.open(dir / "d.csv", columns);
  for (int frame = 0; frame < 6; ++frame) csv.append(row(frame));
  csv.append({6.0, -0.0, std::numeric_limits<double>::denorm_min()});
  CHECK_THROWS_AS(csv.append({7.0, 0.7}), IoError);

  // Rows are on disk as soon as append returns (a crash keeps them).
  std::istringstream lines(read_text(dir / "d.csv"));
  std::string line;
  std::getline(lines, line);
  CHECK(line == "frame,time,energy");
  std::vector<std::vector<double>> rows;
  while (std::getline(lines, line)) {
    std::vector<double> values;
    std::istringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) values.push_back(std::strtod(field.c_str(), nullptr));
    rows.push_back(values);
  }
  REQUIRE(rows.size() == 7);
  for (int frame = 0; frame < 6; ++frame) CHECK(rows[frame] == row(frame));  // exact equality
  CHECK(std::signbit(rows[6][1]));
  CHECK(rows[6][2] == std::numeric_limits<double>::denorm_min());

  // A crash mid-row leaves an incomplete last line; load ignores it and changes nothing, the
  // restart then drops the later frames.
  std::ofstream(dir / "d.csv", std::ios::app) << "7,0.7000";
  const std::string before = read_text(dir / "d.csv");
  io::DiagnosticsCsv restarted;
  restarted.load(dir / "d.csv", columns);
  CHECK(restarted.column("frame").size() == 7);
  CHECK(read_text(dir / "d.csv") == before);
  restarted.keep_until(2);
  CHECK(restarted.column("frame") == std::vector<double>{0, 1, 2});
  restarted.append(row(3));
  CHECK(read_text(dir / "d.csv") ==
        "frame,time,energy\n0,0,0.33333333333333331\n"
        "1,0.10000000000000001,0.25\n2,0.20000000000000001,0.20000000000000001\n"
        "3,0.30000000000000004,0.16666666666666666\n");

  CHECK_THROWS_AS(io::DiagnosticsCsv().load(dir / "d.csv", {"frame", "time"}), IoError);
  CHECK_THROWS_AS(io::DiagnosticsCsv().load(dir / "none.csv", columns), IoError);
  CHECK_THROWS_AS(io::DiagnosticsCsv().open(dir / "e.csv", {"a,b"}), InputError);
}

TEST_CASE("summary JSON parses back with numbers as numbers") {
  const ScratchDir dir("json");
  io::write_summary(dir / "summary.json", {{"third", 1.0 / 3.0}, {"blown_up", std::nan("")}, {"huge", 1e308}},
                    {{"cfl", "0.4"},
                     {"steps", "10"},
                     {"plus", "+5"},
                     {"implicit", "true"},
                     {"off", "False"},
                     {"name", "sand"},
                     {"overflow", "1e400"},
                     {"not_a_number", "nan"},
                     {"blank", ""}},
                    {{"version", "0.1.0"}});
  const auto j = nlohmann::json::parse(read_text(dir / "summary.json"));
  CHECK(j["results"]["third"].is_number_float());
  CHECK(j["results"]["third"].get<double>() == 1.0 / 3.0);
  CHECK(j["results"]["blown_up"].is_null());
  CHECK(j["results"]["huge"].get<double>() == 1e308);
  CHECK(j["parameters"]["cfl"].get<double>() == 0.4);
  CHECK(j["parameters"]["steps"].is_number_integer());
  CHECK(j["parameters"]["steps"].get<int>() == 10);
  CHECK(j["parameters"]["plus"].get<int>() == 5);
  CHECK(j["parameters"]["implicit"] == true);
  CHECK(j["parameters"]["off"] == false);
  CHECK(j["parameters"]["name"] == "sand");
  CHECK(j["parameters"]["overflow"] == "1e400");
  CHECK(j["parameters"]["not_a_number"] == "nan");
  CHECK(j["parameters"]["blank"] == "");
  CHECK(j["info"]["version"] == "0.1.0");
  CHECK(dir.entries() == std::vector<std::string>{"summary.json"});

  CHECK_THROWS_AS(io::write_summary(dir / "dup.json", {{"a", 1.0}, {"a", 2.0}}, {}, {}), InputError);
}
