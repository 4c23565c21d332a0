#pragma once
//! The material index of particles that carry no stress: the discrete grains of a sediment
//! that switches between a granular continuum and discrete grains (libcoupling,
//! docs/coupling.md, "Continuum/discrete switching"). The solid stages treat only the indices
//! of their material list: ReturnMap leaves these particles alone, StressForces gives them no
//! stress when built with `stress_free_particles`, and g2p updates their F like any other (a
//! branch-free loop), which the owner of the switch resets to I every step.
#include <cstdint>
#include <limits>

namespace mpm {

inline constexpr std::uint16_t stress_free_material = std::numeric_limits<std::uint16_t>::max();

}  // namespace mpm
