#pragma once
//! Internal to the I/O module: the writers copy channels by size(), so a particle set whose
//! channels disagree in length would be read out of bounds; they check it first.
#include <mpm/core/error.h>
#include <mpm/core/particles.h>

#include <filesystem>
#include <string>

namespace mpm::io::detail {

template <int dim>
void verify_channel_sizes(const Particles<dim>& p, const std::filesystem::path& file) {
  const std::size_t n = p.size();
  const bool kinematic = p.v.size() == n && p.C.size() == n && p.mass.size() == n &&
                         p.volume0.size() == n && p.material.size() == n;
  const std::size_t nf = p.has_deformation() ? n : 0;
  const bool deformation = p.F.size() == nf && p.plastic.size() == nf;
  if (!kinematic || !deformation)
    throw Error("cannot write '" + file.string() + "': the particle channels differ in length (" +
                std::to_string(n) + " positions)");
}

}  // namespace mpm::io::detail
