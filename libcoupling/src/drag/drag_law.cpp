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

}  // namespace coupling::drag
