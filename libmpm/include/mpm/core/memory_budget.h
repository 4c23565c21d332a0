#pragma once
//! Up-front memory estimates, so that a scene too large for the machine is refused when it is
//! built, with the estimate in the message, instead of allocating for a minute and dying with a
//! bare std::bad_alloc. Seeding asks before it allocates (geometry/seeding.cpp): what this
//! process holds now plus the estimate must fit in what it holds plus the memory available
//! (MemAvailable of /proc/meminfo, read at each request, so earlier bodies count), and under the
//! apps' --max-memory cap.
#include <string>

namespace mpm {

//! Caps the memory this process may hold (--max-memory); the lowest cap given holds.
void cap_memory(double bytes);

//! "" when `bytes` more fit; otherwise why not ("about 400 GB more than the 12 GB held, beyond
//! the 24.8 GB available (MemAvailable)").
std::string memory_shortfall(double bytes);

//! Bytes that still fit: the lower of the memory available and the cap, less what is held.
double memory_headroom();

//! Estimated bytes per particle of a solid or fluid particle set, with the particle's share of
//! the grid and of the sort buffers: the checkpointed channels (x, v, C, F, mass, volume0,
//! plastic, material), seeding's temporary positions, and about one grid node of mass,
//! velocity and force per particle, twice over for the sort.
template <int dim>
constexpr double kBytesPerParticle = dim == 2 ? 250.0 : 450.0;

}  // namespace mpm
