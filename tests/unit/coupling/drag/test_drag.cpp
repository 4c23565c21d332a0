#include <coupling/drag/drag_law.h>
#include <doctest/doctest.h>
#include <mpm/core/config.h>
#include <mpm/core/error.h>

#include <cmath>
#include <string>

using namespace coupling::drag;

namespace {

// Water and fine sand: mu = 1e-3 Pa s, rho_w = 1000 kg/m^3, d = 0.2 mm.
constexpr DragParameters kSand{2.0e-4, 1.0e-3, 1000.0};

DragParameters with_diameter(double d) { return {d, kSand.viscosity, kSand.density}; }

std::string input_error(const std::string& yaml) {
  try {
    parse_drag_law(mpm::Config::parse(yaml, "scene.yaml"));
  } catch (const mpm::InputError& e) {
    return e.what();
  }
  FAIL("expected an InputError");
  return {};
}

}  // namespace

// Expected values below are the published formulas evaluated by hand (Python, double), with the
// inputs in the comment; they do not go through the library's Cd Re form.
TEST_CASE("each law reproduces its published formula at hand-computed points") {
  // Stokes: 18 mu n_s / d^2, n_s = 0.1.
  CHECK(Stokes{kSand}.beta(0.9, 0.05) == doctest::Approx(45000.0).epsilon(1e-13));
  // Schiller-Naumann: n_w = 0.9, u = 0.05 -> Re = 9, Cd = 24/9 (1 + 0.15 9^0.687),
  // beta = 3/4 Cd n_s n_w rho_w u / d.
  CHECK(SchillerNaumann{kSand}.beta(0.9, 0.05) == doctest::Approx(75539.95387620378).epsilon(1e-13));
  // Schiller-Naumann above Re = 1000: d = 5 mm, n_w = 0.95, u = 1 -> Re = 4750, Cd = 0.44.
  CHECK(SchillerNaumann{with_diameter(5e-3)}.beta(0.95, 1.0) == doctest::Approx(3135.0).epsilon(1e-13));
  // Di Felice: n_w = 0.7, u = 0.05 -> Re = 7, chi = 3.17545874831, Cd = (0.63 + 4.8/sqrt 7)^2,
  // beta = 3/4 Cd rho_w u n_s n_w^(2 - chi) / d.
  CHECK(di_felice_exponent(7.0) == doctest::Approx(3.175458748311308).epsilon(1e-13));
  CHECK(DiFelice{kSand}.beta(0.7, 0.05) == doctest::Approx(511078.18414055306).epsilon(1e-12));
  // Di Felice near the minimum of chi: d = 1 mm, n_w = 0.6, u = 0.2 -> Re = 120.
  CHECK(DiFelice{with_diameter(1e-3)}.beta(0.6, 0.2) == doctest::Approx(123210.15369682592).epsilon(1e-12));
  // Gidaspow, Ergun branch: n_w = 0.6, u = 0.05: 150 n_s^2 mu / (n_w d^2) + 1.75 n_s rho_w u / d.
  CHECK(Gidaspow{kSand}.beta(0.6, 0.05) == doctest::Approx(1175000.0).epsilon(1e-13));
  // Gidaspow, Wen-Yu branch: n_w = 0.9, u = 0.05: Schiller-Naumann value above times 0.9^-2.65.
  CHECK(Gidaspow{kSand}.beta(0.9, 0.05) == doctest::Approx(99869.77358843542).epsilon(1e-13));
  // Richardson-Zaki with n = 4.65: the same Wen-Yu value, now also below n_w = 0.8 (n_w = 0.6,
  // u = 0.05 -> Re = 6, Cd = 24/6 (1 + 0.15 6^0.687), times 0.6^-2.65); with n = 3: 0.6^-1.
  CHECK(RichardsonZaki{kSand}.beta(0.9, 0.05) == doctest::Approx(99869.77358843542).epsilon(1e-13));
  CHECK(RichardsonZaki{kSand}.beta(0.6, 0.05) == doctest::Approx(1054877.1024892002).epsilon(1e-12));
  CHECK(RichardsonZaki{kSand, 3.0}.beta(0.6, 0.05) == doctest::Approx(454099.92338210373).epsilon(1e-12));
  // Their exponent correlation (wide column): 4.65 below Re_t = 0.2, 4.35 Re^-0.03 to 1,
  // 4.45 Re^-0.1 to 500, 2.39 above.
  CHECK(richardson_zaki_exponent(0.1) == 4.65);
  CHECK(richardson_zaki_exponent(0.5) == doctest::Approx(4.35 * std::pow(0.5, -0.03)).epsilon(1e-15));
  CHECK(richardson_zaki_exponent(10.0) == doctest::Approx(3.5347606445230526).epsilon(1e-13));
  CHECK(richardson_zaki_exponent(1000.0) == 2.39);
}

TEST_CASE("the Stokes limit of every law has the documented n_w factors") {
  const double stokes = Stokes{kSand}.beta(0.9, 0.0);
  // Schiller-Naumann: exactly Stokes at zero slip, and within Re^0.687 of it at small slip.
  CHECK(SchillerNaumann{kSand}.beta(0.9, 0.0) == doctest::Approx(stokes).epsilon(1e-15));
  CHECK(SchillerNaumann{kSand}.beta(0.9, 1e-15) == doctest::Approx(stokes).epsilon(1e-8));
  // Wen-Yu: Stokes n_w^-2.65.
  CHECK(Gidaspow{kSand}.beta(0.9, 0.0) == doctest::Approx(stokes * std::pow(0.9, -2.65)).epsilon(1e-14));
  // Di Felice: Cd Re -> 4.8^2 = 23.04 and chi -> 3.7: 17.28 mu n_s n_w^-2.7 / d^2.
  const double di_felice_0 = 17.28 * kSand.viscosity * 0.1 * std::pow(0.9, -2.7) / (kSand.diameter * kSand.diameter);
  CHECK(DiFelice{kSand}.beta(0.9, 0.0) == doctest::Approx(di_felice_0).epsilon(1e-14));
  CHECK(DiFelice{kSand}.beta(0.9, 1e-16) == doctest::Approx(di_felice_0).epsilon(1e-7));
}

TEST_CASE("hindered settling implied at low Re: v_s / v_Stokes = n_w^2 beta_Stokes / beta") {
  // Closed column, fluid displaced upward (n_w v_w + n_s v_s = 0), mixture-weight pressure
  // gradient: n_s n_w (rho_s - rho_w) g = beta (v_w - v_s), v_s = n_w (v_s - v_w)
  // => v_s = n_w^2 n_s (rho_s - rho_w) g / beta (docs/coupling.md).
  for (const double n_w : {0.95, 0.85, 0.8}) {
    const double stokes = Stokes{kSand}.beta(n_w, 0.0);
    const auto ratio = [&](double beta) { return n_w * n_w * stokes / beta; };
    CHECK(ratio(Stokes{kSand}.beta(n_w, 0.0)) == doctest::Approx(std::pow(n_w, 2.0)).epsilon(1e-14));
    CHECK(ratio(Gidaspow{kSand}.beta(n_w, 0.0)) == doctest::Approx(std::pow(n_w, 4.65)).epsilon(1e-14));
    CHECK(ratio(DiFelice{kSand}.beta(n_w, 0.0)) == doctest::Approx(std::pow(n_w, 4.7) * 24.0 / 23.04).epsilon(1e-14));
  }
  // Richardson-Zaki: n_w^n at every fraction, the dense ones included.
  for (const double n_w : {0.99, 0.8, 0.6, 0.4})
    for (const double n : {4.65, 2.39, 5.1}) {
      const double stokes = Stokes{kSand}.beta(n_w, 0.0);
      CHECK(n_w * n_w * stokes / RichardsonZaki{kSand, n}.beta(n_w, 0.0) ==
            doctest::Approx(std::pow(n_w, n)).epsilon(1e-14));
    }
}

TEST_CASE("settling_velocity and terminal_velocity: a lone grain, and the Stokes law's hindered speed") {
  constexpr double rho_s = 2650.0, g = 9.81;
  // Stokes: v = (rho_s - rho_w) g d^2 / (18 mu) = 1650 * 9.81 * 4e-8 / 0.018 = 0.03597 m/s for a
  // lone grain, n_w^2 of it in a suspension (the test above).
  const double stokes = 1650.0 * 9.81 * 4.0e-8 / 0.018;
  CHECK(terminal_velocity(Stokes{kSand}, rho_s, g) == doctest::Approx(stokes).epsilon(1e-8));
  CHECK(settling_velocity(Stokes{kSand}, 0.8, rho_s, g) == doctest::Approx(0.64 * stokes).epsilon(1e-12));
  // Di Felice, d = 0.5 mm: Dallavalle's (3/4) Cd rho_w v^2 / d = (rho_s - rho_w) g with
  // Cd = (0.63 + 4.8 / sqrt(Re))^2, Re = rho_w v d / mu, solved by hand: v = 0.0729 m/s.
  const DragParameters sand{5.0e-4, 1.0e-3, 1000.0};
  const double v = terminal_velocity(DiFelice{sand}, rho_s, g);
  const double cd = std::pow(0.63 + 4.8 / std::sqrt(1000.0 * v * 5.0e-4 / 1.0e-3), 2.0);
  CHECK(0.75 * cd * 1000.0 * v * v / 5.0e-4 == doctest::Approx(1650.0 * 9.81).epsilon(1e-6));
  CHECK(v == doctest::Approx(0.0729).epsilon(2e-3));
  // The bisection refuses a force that never reaches the load instead of doubling forever.
  CHECK(root_of_increasing([](double u) { return u; }, 0.5, 1.0) == doctest::Approx(0.5).epsilon(1e-14));
  CHECK_THROWS_AS(root_of_increasing([](double u) { return u / (1.0 + u); }, 2.0, 1.0), mpm::NumericalError);
  CHECK_THROWS_AS(root_of_increasing([](double u) { return u; }, 1.0, 0.0), mpm::NumericalError);
}

TEST_CASE("beta is finite and non-negative, zero without sediment, and nondecreasing in slip") {
  for (const std::string& name : drag_law_names()) {
    CAPTURE(name);
    const DragLaw law = make_drag_law(name, kSand);
    for (double n_w = 0.35; n_w <= 1.0; n_w += 0.01) {
      double previous = 0.0;
      for (double slip = 0.0; slip <= 20.0; slip = 2.0 * slip + 1e-6) {
        const double b = beta(law, n_w, slip);
        REQUIRE(std::isfinite(b));
        REQUIRE(b >= 0.0);
        if (name != "di_felice") REQUIRE(b >= previous);  // chi(Re) makes Di Felice non-monotone
        previous = b;
      }
    }
    CHECK(beta(law, 1.0, 0.3) == 0.0);
  }
}

TEST_CASE("continuity and the published switches") {
  // Schiller-Naumann: Cd jumps from 0.43829 to 0.44 at Re = 1000.
  const double below = schiller_naumann_cd_re(1000.0 - 1e-9) / 1000.0, above = schiller_naumann_cd_re(1000.0) / 1000.0;
  CHECK(below == doctest::Approx(0.43828814001999694).epsilon(1e-9));
  CHECK(above == doctest::Approx(0.44).epsilon(1e-15));
  // Di Felice is smooth in n_w and in the slip (here across Re = 10^1.5, the minimum of chi).
  const DiFelice df{kSand};
  const double slip_min_chi = std::pow(10.0, 1.5) * kSand.viscosity / (0.8 * kSand.density * kSand.diameter);
  CHECK(di_felice_exponent(std::pow(10.0, 1.5)) == doctest::Approx(3.05).epsilon(1e-14));
  CHECK(df.beta(0.8, slip_min_chi * (1 + 1e-8)) == doctest::Approx(df.beta(0.8, slip_min_chi)).epsilon(1e-7));
  CHECK(df.beta(0.8 + 1e-9, 0.1) == doctest::Approx(df.beta(0.8, 0.1)).epsilon(1e-7));
  // Gidaspow: Ergun below n_w = 0.8, Wen-Yu from 0.8 on; at Re -> 0 Ergun is 7.5 mu/d^2 and
  // Wen-Yu 3.6 0.8^-2.65 mu/d^2 there (ratio 1.15331).
  const Gidaspow g{kSand};
  CHECK(g.beta(std::nextafter(0.8, 0.0), 0.0) / g.beta(0.8, 0.0) == doctest::Approx(1.1533131083067483).epsilon(1e-9));
  CHECK(g.beta(0.8, 0.05) ==
        doctest::Approx(SchillerNaumann{kSand}.beta(0.8, 0.05) * std::pow(0.8, -2.65)).epsilon(1e-14));
}

TEST_CASE("parse_drag_law reads the law and validates every key") {
  const DragLaw law = parse_drag_law(mpm::Config::parse(
      "drag: {law: di_felice, grain_diameter: 3.0e-4}\nfluid: {density: 998, viscosity: 1.1e-3}\n", "scene.yaml"));
  CHECK(std::holds_alternative<DiFelice>(law));
  CHECK(parameters(law).diameter == 3.0e-4);
  CHECK(parameters(law).density == 998.0);
  CHECK(parameters(law).viscosity == 1.1e-3);
  // The default law: Richardson-Zaki with the low-Re exponent, or the scene's exponent.
  const DragLaw fallback = parse_drag_law(
      mpm::Config::parse("drag: {grain_diameter: 1.0e-3}\nfluid: {density: 1000, viscosity: 1.0e-3}\n", "scene.yaml"));
  REQUIRE(std::holds_alternative<RichardsonZaki>(fallback));
  CHECK(std::get<RichardsonZaki>(fallback).exponent == 4.65);
  CHECK(std::get<RichardsonZaki>(parse_drag_law(mpm::Config::parse("drag: {grain_diameter: 1.0e-3, exponent: 3.5}\n"
                                                                   "fluid: {density: 1000, viscosity: 1.0e-3}\n",
                                                                   "scene.yaml")))
            .exponent == 3.5);
  const std::string exponent = input_error(
      "drag:\n  law: richardson_zaki\n  grain_diameter: 1.0e-3\n  exponent: 1.5\nfluid: {density: 1000, viscosity: "
      "1.0e-3}\n");
  CHECK(exponent.find("scene.yaml:4") != std::string::npos);
  CHECK(exponent.find("drag.exponent") != std::string::npos);
  CHECK(exponent.find("[2, 6]") != std::string::npos);

  const std::string unknown =
      input_error("drag: {law: ergun, grain_diameter: 1.0e-3}\nfluid: {density: 1000, viscosity: 1.0e-3}\n");
  CHECK(unknown.find("scene.yaml:1") != std::string::npos);
  CHECK(unknown.find("drag.law") != std::string::npos);
  CHECK(unknown.find("ergun") != std::string::npos);
  CHECK(unknown.find("gidaspow") != std::string::npos);

  const std::string diameter =
      input_error("drag:\n  law: stokes\n  grain_diameter: 0\nfluid: {density: 1000, viscosity: 1.0e-3}\n");
  CHECK(diameter.find("scene.yaml:3") != std::string::npos);
  CHECK(diameter.find("drag.grain_diameter") != std::string::npos);
  CHECK(diameter.find("> 0") != std::string::npos);

  const std::string viscosity =
      input_error("drag: {law: stokes, grain_diameter: 1.0e-3}\nfluid:\n  density: 1000\n  viscosity: 0\n");
  CHECK(viscosity.find("scene.yaml:4") != std::string::npos);
  CHECK(viscosity.find("fluid.viscosity") != std::string::npos);

  CHECK(input_error("fluid: {density: 1000, viscosity: 1.0e-3}\n").find("drag") != std::string::npos);
  CHECK_THROWS_AS(make_drag_law("ergun", kSand), mpm::InputError);
}
