#pragma once
//! The drag laws a scene can choose, as one closed std::variant (visited outside the node
//! loop, like mpm::constitutive::ElasticModel). Each alternative is a value struct with the
//! grain and fluid parameters and
//!   double beta(double n_w, double slip) const;   // [kg/(m^3 s)], >= 0
//! (conventions in drag_parameters.h). Scene keys:
//!   drag:
//!     law: richardson_zaki    # richardson_zaki (default) | stokes | schiller_naumann |
//!                             # di_felice | gidaspow
//!     grain_diameter: 2.0e-4  # d [m] > 0
//!     exponent: 4.65          # n in [2, 6], richardson_zaki only
//!   fluid:
//!     density: 1000           # rho_w [kg/m^3] > 0 (the fluid scene's key)
//!     viscosity: 1.0e-3       # mu [Pa s] > 0 (the fluid scene's key; drag needs mu > 0)
#include <coupling/drag/di_felice.h>
#include <coupling/drag/drag_parameters.h>
#include <coupling/drag/gidaspow.h>
#include <coupling/drag/richardson_zaki.h>
#include <coupling/drag/schiller_naumann.h>
#include <coupling/drag/stokes.h>
#include <mpm/core/config.h>

#include <functional>
#include <string>
#include <variant>
#include <vector>

namespace coupling::drag {

using DragLaw = std::variant<RichardsonZaki, Stokes, SchillerNaumann, DiFelice, Gidaspow>;

//! Scene-file names of the alternatives, in variant order.
std::vector<std::string> drag_law_names();

//! The law called `name` (one of drag_law_names()) with parameters `p`; InputError otherwise.
DragLaw make_drag_law(const std::string& name, const DragParameters& p);

//! Reads `drag.law`, `drag.grain_diameter` (and `drag.exponent` of richardson_zaki),
//! `fluid.density` and `fluid.viscosity` of a scene;
//! a missing key, an unknown law or a value out of range is an InputError naming the file,
//! line, key, value and accepted range.
DragLaw parse_drag_law(const mpm::Config& scene);

//! beta [kg/(m^3 s)] of whichever law `law` holds (one visit per call: not for node loops).
double beta(const DragLaw& law, double n_w, double slip);

//! The grain and fluid parameters of whichever law `law` holds.
const DragParameters& parameters(const DragLaw& law);

//! The settling speed [m/s] the law implies for grains of density `sediment_density` [kg/m^3]
//! at fluid fraction n_w in (0, 1) in a closed column under gravity `gravity` [m/s^2]: the
//! steady balance n_s n_w (rho_s - rho_w) g = beta(n_w, u) u with the fluid's return flow
//! n_w v_w + n_s v_s = 0, so the slip is u = v_s / n_w (docs/coupling.md, "Settling"); as
//! n_w -> 1 the law's single-grain terminal velocity.
double settling_velocity(const DragLaw& law, double n_w, double sediment_density, double gravity);

//! The law's terminal velocity [m/s] of one grain of density `sediment_density` [kg/m^3] in
//! unbounded fluid: settling_velocity at n_w = 1 - 1e-9 (every law's beta is linear in the
//! 1 - n_w of the load, so the limit is exact to that n_s).
double terminal_velocity(const DragLaw& law, double sediment_density, double gravity);

//! The root u >= 0 of force(u) = load >= 0 for a force that grows with u from force(0) = 0
//! (bisection from [0, guess], guess > 0, the bracket doubled until it holds the root; a
//! NumericalError where 2^64 guess does not reach the load).
double root_of_increasing(const std::function<double(double)>& force, double load, double guess);

}  // namespace coupling::drag
