#include <coupling/drag/drag_law.h>
#include <mpm/core/error.h>

#include <utility>

namespace coupling::drag {

namespace {

template <std::size_t... I>
std::vector<std::string> names(std::index_sequence<I...>) {
  return {std::string(std::variant_alternative_t<I, DragLaw>::name)...};
}

template <std::size_t... I>
DragLaw make(const std::string& name, const DragParameters& p, std::index_sequence<I...>) {
  DragLaw law;
  const bool found =
      ((name == std::variant_alternative_t<I, DragLaw>::name ? (law = std::variant_alternative_t<I, DragLaw>{p}, true)
                                                             : false) ||
       ...);
  if (!found) throw mpm::InputError("unknown drag law '" + name + "'");
  return law;
}

constexpr auto alternatives = std::make_index_sequence<std::variant_size_v<DragLaw>>();

}  // namespace

std::vector<std::string> drag_law_names() { return names(alternatives); }

DragLaw make_drag_law(const std::string& name, const DragParameters& p) { return make(name, p, alternatives); }

DragLaw parse_drag_law(const mpm::Config& scene) {
  const mpm::Config drag = scene.child("drag");
  const std::string name = drag.choice("law", std::string(RichardsonZaki::name), drag_law_names());
  DragParameters p;
  p.diameter = drag.number("grain_diameter", mpm::Range::positive());
  const mpm::Config fluid = scene.child("fluid");
  p.density = fluid.number("density", mpm::Range::positive());
  p.viscosity = fluid.number("viscosity", mpm::Range::positive());
  DragLaw law = make_drag_law(name, p);
  if (auto* hindered = std::get_if<RichardsonZaki>(&law))
    hindered->exponent = drag.number("exponent", RichardsonZaki::low_reynolds_exponent, mpm::Range::closed(2.0, 6.0));
  return law;
}

double beta(const DragLaw& law, double n_w, double slip) {
  return std::visit([&](const auto& l) { return l.beta(n_w, slip); }, law);
}

const DragParameters& parameters(const DragLaw& law) {
  return std::visit([](const auto& l) -> const DragParameters& { return l.p; }, law);
}

double settling_velocity(const DragLaw& law, double n_w, double sediment_density, double gravity) {
  const DragParameters& p = parameters(law);
  const double load = (1.0 - n_w) * n_w * (sediment_density - p.density) * gravity;  // [N/m^3]
  return n_w * root_of_increasing([&](double u) { return beta(law, n_w, u) * u; }, load,
                                  p.stokes_velocity(sediment_density, gravity));
}

double terminal_velocity(const DragLaw& law, double sediment_density, double gravity) {
  return settling_velocity(law, 1.0 - 1e-9, sediment_density, gravity);
}

double root_of_increasing(const std::function<double(double)>& force, double load, double guess) {
  mpm::verify<mpm::NumericalError>(guess > 0.0 && load >= 0.0, "root_of_increasing: expected guess > 0, load >= 0");
  double lo = 0.0, hi = guess;
  for (int doublings = 0; force(hi) < load; ++doublings) {
    mpm::verify<mpm::NumericalError>(doublings < 64, "root_of_increasing: the force does not reach the load");
    hi *= 2.0;
  }
  for (int i = 0; i < 200; ++i) {
    const double u = 0.5 * (lo + hi);
    (force(u) < load ? lo : hi) = u;
  }
  return 0.5 * (lo + hi);
}

}  // namespace coupling::drag
