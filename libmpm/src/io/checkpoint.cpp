#include <mpm/io/checkpoint.h>

#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>

#include "channel_sizes.h"
#include "hdf5_file.h"

#include <sstream>
#include <utility>

namespace mpm::io {
namespace {

constexpr const char* kFormat = "mpm-checkpoint";
constexpr std::int32_t kVersion = 1;

// Eigen's fixed-size vectors and matrices are plain arrays of doubles, so a channel is one
// contiguous block of N * rows * cols doubles.
static_assert(sizeof(Vec<2>) == 2 * sizeof(double) && sizeof(Vec<3>) == 3 * sizeof(double));
static_assert(sizeof(Mat<2>) == 4 * sizeof(double) && sizeof(Mat<3>) == 9 * sizeof(double));

template <class Matrix>
const double* doubles(const std::vector<Matrix>& channel) {
  return channel.empty() ? nullptr : channel.front().data();
}
template <class Matrix>
double* doubles(std::vector<Matrix>& channel) {
  return channel.empty() ? nullptr : channel.front().data();
}

//! "x" of the unnamed phase, "fluid/x" of the phase "fluid"; likewise for root attributes.
std::string dataset(const std::string& phase, const std::string& name) {
  return phase.empty() ? name : phase + "/" + name;
}
std::string attribute(const std::string& phase, const std::string& name) {
  return phase.empty() ? name : phase + "." + name;
}

}  // namespace

template <int dim>
void save_checkpoint(const std::filesystem::path& path, const std::vector<CheckpointPhase<dim>>& phases,
                     const CheckpointHeader& header) {
  AtomicFile out(path);
  {
    using detail::Hdf5File;
    Hdf5File file(out.temp_path(), Hdf5File::Mode::create, path);
    for (const auto& [name, particles] : phases) {
      const Particles<dim>& p = *particles;
      detail::verify_channel_sizes(p, path);
      const hsize_t n = p.size(), nf = p.has_deformation() ? n : 0, d = dim, dd = dim * dim;
      const auto at = [&](const char* channel) { return dataset(name, channel); };
      file.write(at("x"), doubles(p.x), {n, d});
      file.write(at("v"), doubles(p.v), {n, d});
      file.write(at("C"), doubles(p.C), {n, dd});
      file.write(at("mass"), p.mass.data(), {n});
      file.write(at("volume0"), p.volume0.data(), {n});
      file.write(at("material"), p.material.data(), {n});
      file.write(at("F"), doubles(p.F), {nf, dd});
      file.write(at("plastic"), p.plastic.data(), {nf});
      file.write_attribute<std::int32_t>(attribute(name, "deformation"), p.has_deformation());
    }
    file.write_attribute("format", std::string(kFormat));
    file.write_attribute("version", kVersion);
    file.write_attribute<std::int32_t>("dim", dim);
    file.write_attribute<std::int32_t>("frame", header.frame);
    file.write_attribute<std::int64_t>("step", header.step);
    file.write_attribute("time", header.time);
    file.write_attribute("dt_previous", header.dt_previous);
    file.write_attribute("scene_digest", header.scene_digest);
    std::string names;
    for (const auto& [name, values] : header.stage_data) {
      verify<InputError>(name.find('\n') == std::string::npos, "checkpoint: stage data name with a newline");
      file.write("stages/" + name, values.data(), {values.size()});
      names += (names.empty() ? "" : "\n") + name;
    }
    file.write_attribute("stage_data", names);
    file.close();
  }
  out.commit();
}

template <int dim>
Particles<dim> load_checkpoint(const std::filesystem::path& path, CheckpointHeader& header,
                               const std::string& phase) {
  using detail::Hdf5File;
  const Hdf5File file(path, Hdf5File::Mode::read);
  const std::string name = "'" + path.string() + "'";
  if (!file.has_attribute("format") || file.read_string_attribute("format") != kFormat)
    throw InputError(name + " is not an MPM checkpoint (no format attribute '" + kFormat + "')");
  const auto version = file.read_attribute<std::int32_t>("version");
  if (version != kVersion)
    throw InputError("checkpoint " + name + " has version " + std::to_string(version) +
                     "; this program reads version " + std::to_string(kVersion));
  const auto stored_dim = file.read_attribute<std::int32_t>("dim");
  if (stored_dim != dim)
    throw InputError("checkpoint " + name + " holds a " + std::to_string(stored_dim) +
                     "D scene; this program is " + std::to_string(dim) + "D");

  // Filled locally so that a corrupt file leaves the caller's header untouched.
  CheckpointHeader loaded;
  loaded.dim = stored_dim;
  loaded.frame = file.read_attribute<std::int32_t>("frame");
  loaded.step = file.read_attribute<std::int64_t>("step");
  loaded.time = file.read_attribute<double>("time");
  loaded.dt_previous = file.read_attribute<double>("dt_previous");
  loaded.scene_digest = file.read_string_attribute("scene_digest");
  if (file.has_attribute("stage_data")) {
    std::stringstream names(file.read_string_attribute("stage_data"));
    for (std::string entry; std::getline(names, entry);) {
      const detail::Shape shape = file.shape("stages/" + entry);
      if (shape.size() != 1) throw IoError("checkpoint " + name + " is corrupt: stages/" + entry + " is not 1D");
      std::vector<double> values(shape[0]);
      file.read("stages/" + entry, values.data(), shape);
      loaded.stage_data.emplace_back(entry, std::move(values));
    }
  }

  if (!file.has_attribute(attribute(phase, "deformation")))
    throw InputError("checkpoint " + name + " holds no particle phase '" + phase + "'");
  const auto at = [&](const char* channel) { return dataset(phase, channel); };
  const detail::Shape x_shape = file.shape(at("x"));
  if (x_shape.size() != 2)
    throw IoError("checkpoint " + name + " is corrupt: dataset x is not N x " +
                  std::to_string(dim));
  const bool deformation = file.read_attribute<std::int32_t>(attribute(phase, "deformation")) != 0;
  const hsize_t n = x_shape[0], nf = deformation ? n : 0, d = dim, dd = dim * dim;

  Particles<dim> p;
  // The flag matters even without particles: particles added later get F = I.
  if (deformation) p.enable_deformation();
  p.x.resize(n);
  p.v.resize(n);
  p.C.resize(n);
  p.mass.resize(n);
  p.volume0.resize(n);
  p.material.resize(n);
  p.F.resize(nf);
  p.plastic.resize(nf);
  file.read(at("x"), doubles(p.x), {n, d});
  file.read(at("v"), doubles(p.v), {n, d});
  file.read(at("C"), doubles(p.C), {n, dd});
  file.read(at("mass"), p.mass.data(), {n});
  file.read(at("volume0"), p.volume0.data(), {n});
  file.read(at("material"), p.material.data(), {n});
  file.read(at("F"), doubles(p.F), {nf, dd});
  file.read(at("plastic"), p.plastic.data(), {nf});
  header = std::move(loaded);
  return p;
}

template void save_checkpoint<2>(const std::filesystem::path&, const std::vector<CheckpointPhase<2>>&,
                                 const CheckpointHeader&);
template void save_checkpoint<3>(const std::filesystem::path&, const std::vector<CheckpointPhase<3>>&,
                                 const CheckpointHeader&);
template Particles<2> load_checkpoint<2>(const std::filesystem::path&, CheckpointHeader&, const std::string&);
template Particles<3> load_checkpoint<3>(const std::filesystem::path&, CheckpointHeader&, const std::string&);

}  // namespace mpm::io
