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
  p.for_each_channel([&](const ChannelInfo& info, const auto& values) {
    if (values.size() != n)
      throw Error("cannot write '" + file.string() + "': the particle channels differ in length (" + std::to_string(n) +
                  " positions, " + std::to_string(values.size()) + " values of '" + info.name + "')");
  });
}

}  // namespace mpm::io::detail
