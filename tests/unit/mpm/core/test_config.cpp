#include <mpm/core/command_line.h>
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/core/scene_settings.h>

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

namespace {

//! The InputError message thrown by `action`; fails the test when nothing is thrown.
template <class Action>
std::string input_error(Action action) {
  try {
    action();
  } catch (const mpm::InputError& e) {
    return e.what();
  }
  FAIL("expected an InputError");
  return {};
}

const char* const kScene = R"(solid:
  density: 1000
  youngs_modulus: -5
  poisson_ratio: 0.3
  model: neo_hookian
  name: [1, 2]
gravity: [0, -9.81]
origin: [0, 0, 0]
steps: 2.5
bodies:
  - shape: box
    size: [1, 1]
  - shape: sphere
    radius: 0.5
)";

}  // namespace

TEST_CASE("Range describes and contains its interval") {
  using mpm::Range;
  CHECK(Range::positive().describe() == "> 0");
  CHECK(Range::non_negative().describe() == ">= 0");
  CHECK(Range::open(-1, 0.5).describe() == "in (-1, 0.5)");
  CHECK(Range::half_open(0, 90).describe() == "in [0, 90)");
  CHECK(Range::any().describe() == "any number");
  CHECK_FALSE(Range::positive().contains(0.0));
  CHECK(Range::non_negative().contains(0.0));
  CHECK(Range::half_open(0, 90).contains(0.0));
  CHECK_FALSE(Range::half_open(0, 90).contains(90.0));
  CHECK_FALSE(Range::open(-1, 0.5).contains(-1.0));
  CHECK(Range::open(-1, 0.5).contains(0.4999));
}

TEST_CASE("valid values are returned exactly") {
  const auto scene = mpm::Config::parse(kScene, "scene.yaml");
  const auto solid = scene.child("solid");
  CHECK(solid.path() == "solid");
  CHECK(solid.number("density", mpm::Range::positive()) == 1000.0);
  CHECK(solid.number("poisson_ratio", mpm::Range::open(-1, 0.5)) == 0.3);
  CHECK(scene.vector<2>("gravity") == mpm::Vec<2>(0.0, -9.81));
  CHECK(scene.vector<3>("origin", mpm::Range::non_negative()) == mpm::Vec<3>::Zero());
  CHECK(scene.integer("threads", 4, 1, 64) == 4);
  CHECK(scene.flag("verbose", true));
  CHECK(scene.text("title", "untitled") == "untitled");
}

TEST_CASE("errors name file, line, column, key path, value and accepted range") {
  const auto scene = mpm::Config::parse(kScene, "scene.yaml");
  const auto solid = scene.child("solid");

  SUBCASE("out of range") {
    CHECK(input_error([&] { solid.number("youngs_modulus", mpm::Range::positive()); }) ==
          "scene.yaml:3:19: key 'solid.youngs_modulus' = -5: expected a number > 0");
  }
  SUBCASE("wrong type") {
    CHECK(input_error([&] { solid.number("model", mpm::Range::any()); }) ==
          "scene.yaml:5:10: key 'solid.model' = neo_hookian: expected a number");
    CHECK(input_error([&] { solid.text("name"); }) ==
          "scene.yaml:6:9: key 'solid.name' = [1, 2]: expected a string, got a list");
    CHECK(input_error([&] { scene.child("gravity"); }) ==
          "scene.yaml:7:10: key 'gravity' = [0, -9.81]: expected a map of keys, got a list");
  }
  SUBCASE("integer rejects fractions") {
    CHECK(input_error([&] { scene.integer("steps", 1, 0, 100); }) ==
          "scene.yaml:9:8: key 'steps' = 2.5: expected an integer in [0, 100]");
  }
  SUBCASE("missing required key") {
    CHECK(input_error([&] { solid.number("yield_stress", mpm::Range::positive()); }) ==
          "scene.yaml:2:3: key 'solid.yield_stress': missing required key");
  }
  SUBCASE("bad choice lists the allowed values") {
    CHECK(input_error([&] {
            solid.choice("model", "neo_hookean", {"neo_hookean", "fixed_corotated"});
          }) == "scene.yaml:5:10: key 'solid.model' = neo_hookian: expected one of 'neo_hookean', 'fixed_corotated'");
  }
  SUBCASE("wrong vector length") {
    CHECK(input_error([&] { scene.vector<3>("gravity"); }) ==
          "scene.yaml:7:10: key 'gravity' = [0, -9.81]: expected a list of 3 numbers");
  }
  SUBCASE("vector entry out of range") {
    CHECK(input_error([&] { scene.vector<2>("gravity", mpm::Range::non_negative()); }) ==
          "scene.yaml:7:14: key 'gravity[1]' = -9.81: expected a number >= 0");
  }
  SUBCASE("custom cross-field check") {
    CHECK(input_error([&] { solid.fail("density", "must exceed the fluid density"); }) ==
          "scene.yaml:2:12: key 'solid.density' = 1000: must exceed the fluid density");
  }
}

TEST_CASE("non-finite numbers are rejected") {
  const auto scene = mpm::Config::parse("a: .nan\nb: -.inf\nc: inf\n", "s.yaml");
  CHECK(input_error([&] { scene.number("a", mpm::Range::any()); }) ==
        "s.yaml:1:4: key 'a' = .nan: expected a finite number");
  CHECK(input_error([&] { scene.number("b", mpm::Range::any()); }) ==
        "s.yaml:2:4: key 'b' = -.inf: expected a finite number");
  CHECK(input_error([&] { scene.number("c", mpm::Range::any()); }) ==
        "s.yaml:3:4: key 'c' = inf: expected a finite number");
}

TEST_CASE("list elements carry indexed key paths") {
  const auto scene = mpm::Config::parse(kScene, "scene.yaml");
  const auto bodies = scene.list("bodies");
  REQUIRE(bodies.size() == 2);
  CHECK(bodies[1].path() == "bodies[1]");
  CHECK(bodies[0].choice("shape", "box", {"box", "sphere"}) == "box");
  CHECK(input_error([&] { bodies[1].choice("shape", "box", {"box"}); }) ==
        "scene.yaml:13:12: key 'bodies[1].shape' = sphere: expected one of 'box'");
  CHECK(input_error([&] { bodies[0].number("radius", mpm::Range::positive()); }) ==
        "scene.yaml:11:5: key 'bodies[0].radius': missing required key");
  CHECK(scene.list("absent").empty());
  CHECK_FALSE(scene.optional_child("absent").has_value());
}

TEST_CASE("unknown keys fail with a did-you-mean suggestion") {
  const auto scene = mpm::Config::parse("solid:\n  density: 1\n  youngs_modulos: 5\n", "scene.yaml");
  const auto solid = scene.child("solid");
  solid.number("density", mpm::Range::positive());
  solid.number("youngs_modulus", 1e6, mpm::Range::positive());
  CHECK(input_error([&] { scene.reject_unknown_keys(); }) ==
        "scene.yaml:3:3: unknown key 'solid.youngs_modulos' (did you mean 'youngs_modulus'?)");

  const auto unrelated = mpm::Config::parse("a: 1\nzzzzzz: 2\n", "u.yaml");
  unrelated.number("a", mpm::Range::any());
  CHECK(input_error([&] { unrelated.reject_unknown_keys(); }) == "u.yaml:2:1: unknown key 'zzzzzz'");
}

TEST_CASE("reject_unknown_keys walks nested maps and lists") {
  const auto scene = mpm::Config::parse(kScene, "scene.yaml");
  const auto solid = scene.child("solid");
  solid.number("density", mpm::Range::positive());
  solid.number("youngs_modulus", mpm::Range::any());
  solid.number("poisson_ratio", mpm::Range::any());
  scene.vector<2>("gravity");
  scene.vector<3>("origin");
  scene.number("steps", mpm::Range::any());
  const auto bodies = scene.list("bodies");
  bodies[0].text("shape");
  bodies[0].vector<2>("size");
  bodies[1].text("shape");
  // has() on a scalar does not count as reading it.
  CHECK(solid.has("model"));
  CHECK(input_error([&] { scene.reject_unknown_keys(); }) == "scene.yaml:5:3: unknown key 'solid.model'");
  solid.text("model");
  CHECK(input_error([&] { scene.reject_unknown_keys(); }) == "scene.yaml:6:3: unknown key 'solid.name'");
  solid.vector<2>("name");
  CHECK(input_error([&] { scene.reject_unknown_keys(); }) == "scene.yaml:14:5: unknown key 'bodies[1].radius'");
  bodies[1].number("radius", mpm::Range::positive());
  CHECK_NOTHROW(scene.reject_unknown_keys());
}

TEST_CASE("command-line overrides replace values and report their origin") {
  const auto scene = mpm::Config::parse(
      kScene, "scene.yaml",
      {"solid.youngs_modulus=1e6", "gravity=[0, -1]", "bodies.1.radius=-2", "fluid.cfl=0.4", "--x=[1,2]"});
  const auto solid = scene.child("solid");
  CHECK(solid.number("youngs_modulus", mpm::Range::positive()) == 1e6);
  CHECK(scene.vector<2>("gravity") == mpm::Vec<2>(0.0, -1.0));
  CHECK(scene.child("fluid").number("cfl", mpm::Range::open(0, 1)) == 0.4);
  CHECK(input_error([&] { scene.list("bodies")[1].number("radius", mpm::Range::positive()); }) ==
        "command line --set bodies.1.radius=-2: key 'bodies[1].radius' = -2: expected a number > 0");
  CHECK(input_error([&] { scene.vector<3>("--x"); }) ==
        "command line --set --x=[1,2]: key '--x' = [1, 2]: expected a list of 3 numbers");

  CHECK(input_error([&] { mpm::Config::parse(kScene, "scene.yaml", {"solid.density"}); }) ==
        "command line --set solid.density: expected key.path=value");
  CHECK(input_error([&] { mpm::Config::parse(kScene, "scene.yaml", {"bodies.7.radius=1"}); }).find("no index") !=
        std::string::npos);
  CHECK(input_error([&] { mpm::Config::parse(kScene, "scene.yaml", {"steps.x=1"}); }) ==
        "command line --set steps.x=1: key 'steps' = 2.5 is not a map");
}

TEST_CASE("resolved() lists every read value once, defaults included, in reading order") {
  const auto scene = mpm::Config::parse(kScene, "scene.yaml", {"solid.density=2000"});
  const auto solid = scene.child("solid");
  solid.number("density", mpm::Range::positive());
  scene.number("dt", 1e-4, mpm::Range::positive());
  scene.vector<2>("gravity");
  solid.number("density", mpm::Range::positive());
  scene.flag("verbose", false);
  scene.list("bodies")[0].text("shape");
  const std::vector<std::pair<std::string, std::string>> expected = {{"solid.density", "2000"},
                                                                     {"dt", "1e-04"},
                                                                     {"gravity", "[0, -9.81]"},
                                                                     {"verbose", "false"},
                                                                     {"bodies[0].shape", "box"}};
  const auto resolved = scene.resolved();
  REQUIRE(resolved.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    CHECK(resolved[i].first == expected[i].first);
    CHECK(resolved[i].second == expected[i].second);
  }
}

TEST_CASE("unreadable input names the file") {
  CHECK(input_error([] { mpm::Config::load("/nonexistent/scene.yaml"); }).find("/nonexistent/scene.yaml") == 0);
  CHECK(input_error([] { mpm::Config::parse("a: 1\nb: [1, 2\n", "bad.yaml"); }).rfind("bad.yaml:", 0) == 0);
  CHECK(input_error([] { mpm::Config::parse("a: 1\n  b: 2\n", "bad.yaml"); }).rfind("bad.yaml:2:", 0) == 0);
}

TEST_CASE("parse_command_line fills the shared contract") {
  const auto scene = std::filesystem::temp_directory_path() / "mpm_test_config_scene.yaml";
  std::ofstream(scene) << "a: 1\n";
  const std::string file = scene.string();
  std::vector<std::string> args = {"app", file, "--set", "a.b=1", "--set=c=[1,2]", "--check", "--quiet"};
  std::vector<char*> argv;
  for (auto& arg : args) argv.push_back(arg.data());
  const mpm::CommandLine cl = mpm::parse_command_line(int(argv.size()), argv.data(), "app", "test");
  CHECK(cl.scene_file == file);
  CHECK(cl.overrides == std::vector<std::string>{"a.b=1", "c=[1,2]"});
  CHECK(cl.out_dir == "out/app");
  CHECK(cl.check);
  CHECK(cl.quiet);
  CHECK_FALSE(cl.restart.has_value());

  std::vector<std::string> args2 = {"app", "--out", "results", file, "--restart", file};
  argv.clear();
  for (auto& arg : args2) argv.push_back(arg.data());
  const mpm::CommandLine cl2 = mpm::parse_command_line(int(argv.size()), argv.data(), "app", "test");
  CHECK(cl2.out_dir == "results");
  CHECK(cl2.restart == file);
  CHECK_FALSE(cl2.check);
  std::filesystem::remove(scene);
}

TEST_CASE("a key given twice is an error naming both lines, at any depth") {
  // yaml-cpp answers a lookup with the first of two equal keys: without the check, appending
  // `time: {end: 0.1}` to a scene would leave the run at the first time.end.
  CHECK(input_error([] { mpm::Config::parse("time: {end: 1}\ngravity: [0, -9.81]\ntime: {end: 0.1}\n", "s.yaml"); }) ==
        "s.yaml:3:1: key 'time' is given twice (first at line 1); give each key once");
  CHECK(input_error([] { mpm::Config::parse("solid:\n  density: 1000\n  density: 2000\n", "s.yaml"); }) ==
        "s.yaml:3:3: key 'solid.density' is given twice (first at line 2); give each key once");
  CHECK(input_error([] { mpm::Config::parse("bodies:\n  - {shape: box, shape: sphere}\n", "s.yaml"); }) ==
        "s.yaml:2:18: key 'bodies[0].shape' is given twice (first at line 2); give each key once");
  // Overrides replace a key; they never add a second one.
  CHECK_NOTHROW(mpm::Config::parse("time: {end: 1}\n", "s.yaml", {"time.end=2"}));
}

TEST_CASE("a frame count beyond the bound is refused, not overflowed") {
  const std::string scene =
      "dim: 2\ndomain: {lo: [0, 0], hi: [1, 1]}\ngrid: {dx: 0.1}\ntime: {end: 3.0e9, frame_dt: 1}\n";
  const std::string why = input_error([&] { mpm::parse_scene_settings<2>(mpm::Config::parse(scene, "s.yaml")); });
  CHECK(why.find("key 'time.frame_dt' = 1") != std::string::npos);
  CHECK(why.find("gives 3e+09 frames") != std::string::npos);
  CHECK(why.find("at most 10000000") != std::string::npos);
  const auto ok = mpm::parse_scene_settings<2>(mpm::Config::parse(scene, "s.yaml", {"time.end=1.0e7"}));
  CHECK(ok.frame_count() == 10000000);
}
