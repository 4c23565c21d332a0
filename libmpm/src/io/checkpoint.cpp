#include <mpm/io/checkpoint.h>

#include <mpm/core/error.h>
#include <mpm/io/atomic_file.h>
#include <mpm/io/checksum.h>

#include "channel_sizes.h"
#include "hdf5_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace mpm::io {
namespace {

constexpr const char* kFormat = "mpm-checkpoint";
// 3: checksums, run id, frame_step and input digests (2 listed the channels of a phase in
// "<phase>.channels"; 1 had fixed datasets and a deformation flag).
constexpr std::int32_t kVersion = 3;

// Eigen's fixed-size vectors and matrices are plain arrays of doubles, so a channel is one
// contiguous block of N * rows * cols doubles.
static_assert(sizeof(Vec<2>) == 2 * sizeof(double) && sizeof(Vec<3>) == 3 * sizeof(double));
static_assert(sizeof(Mat<2>) == 4 * sizeof(double) && sizeof(Mat<3>) == 9 * sizeof(double));

//! The first scalar of a channel (nullptr when it is empty): its values as HDF5 reads and writes them.
template <class Channel>
auto* scalars(Channel& values) {
  using T = typename std::remove_const_t<Channel>::value_type;
  if constexpr (std::is_arithmetic_v<T>) {
    return values.data();
  } else {
    decltype(values.front().data()) first = nullptr;
    if (!values.empty()) first = values.front().data();
    return first;
  }
}

//! The dataset shape of n values of T: N x dim for a vector, N x dim*dim for a matrix, else N.
template <int dim, class T>
detail::Shape shape_of(hsize_t n) {
  if constexpr (std::is_same_v<T, Vec<dim>>)
    return {n, hsize_t(dim)};
  else if constexpr (std::is_same_v<T, Mat<dim>>)
    return {n, hsize_t(dim * dim)};
  else
    return {n};
}

std::string describe(const detail::Shape& shape) {
  std::string text;
  for (const hsize_t d : shape) text += (text.empty() ? "" : " x ") + std::to_string(d);
  return text;
}

//! "x" of the unnamed phase, "fluid/x" of the phase "fluid"; likewise for root attributes.
std::string dataset(const std::string& phase, const std::string& name) {
  return phase.empty() ? name : phase + "/" + name;
}
std::string attribute(const std::string& phase, const std::string& name) {
  return phase.empty() ? name : phase + "." + name;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> found;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) found.push_back(line);
  return found;
}

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text.empty() ? "none" : text;
}

std::string inputs_text(const std::vector<InputFile>& inputs) {
  std::string text;
  for (const InputFile& f : inputs) {
    verify<InputError>((f.key + f.path + f.digest).find_first_of("\t\n") == std::string::npos,
                       "checkpoint: input file '" + f.path + "' has a tab or line break in its name");
    text += (text.empty() ? "" : "\n") + f.key + "\t" + f.path + "\t" + f.digest;
  }
  return text;
}

std::vector<InputFile> parse_inputs(const std::string& text, const std::string& name) {
  std::vector<InputFile> inputs;
  for (const std::string& line : lines(text)) {
    const std::size_t a = line.find('\t'), b = line.find('\t', a == std::string::npos ? a : a + 1);
    if (b == std::string::npos) throw IoError("checkpoint " + name + " is corrupt: input entry '" + line + "'");
    inputs.push_back({line.substr(0, a), line.substr(a + 1, b - a - 1), line.substr(b + 1)});
  }
  return inputs;
}

//! The checksum of one channel, its name included. A phase's checksum xors those of its channels,
//! so it does not depend on the order in which a scene declares them.
template <class T>
std::uint64_t channel_checksum(const std::string& name, const std::vector<T>& values) {
  Checksum sum;
  sum.add(name);
  sum.add(values.data(), values.size() * sizeof(T));
  return sum.value();
}

//! The checksum of everything in the header that a restart uses.
std::string header_checksum(const CheckpointHeader& h, int dim) {
  Checksum sum;
  const std::int64_t integers[] = {dim, h.frame, h.step, h.frame_step};
  sum.add(integers, sizeof integers);
  sum.add(&h.time, sizeof h.time);
  sum.add(&h.dt_previous, sizeof h.dt_previous);
  sum.add(h.scene_digest);
  sum.add(h.run_id);
  sum.add(inputs_text(h.inputs));
  for (const auto& [name, values] : h.stage_data) {
    sum.add(name);
    sum.add(values.data(), values.size() * sizeof(double));
  }
  return sum.hex();
}

}  // namespace

std::string file_digest(const std::filesystem::path& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw IoError("cannot read '" + path.string() + "' to take its digest: " + std::strerror(errno));
  Checksum sum;
  std::vector<char> buffer(1 << 20);
  for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), file)) > 0;) sum.add(buffer.data(), n);
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) throw IoError("cannot read '" + path.string() + "' to take its digest");
  return sum.hex();
}

template <int dim>
std::string save_checkpoint(const std::filesystem::path& path, const std::vector<CheckpointPhase<dim>>& phases,
                            const CheckpointHeader& header) {
  AtomicFile out(path);
  Checksum all;
  {
    using detail::Hdf5File;
    Hdf5File file(out.temp_path(), Hdf5File::Mode::create, path);
    for (const auto& [name, particles] : phases) {
      const Particles<dim>& p = *particles;
      detail::verify_channel_sizes(p, path);
      std::string stored;
      std::uint64_t checksum = 0;
      p.for_each_channel([&](const ChannelInfo& info, const auto& values) {
        if (!info.use.checkpoint) return;
        using T = typename std::decay_t<decltype(values)>::value_type;
        file.write(dataset(name, info.name), scalars(values), shape_of<dim, T>(values.size()));
        stored += (stored.empty() ? "" : "\n") + info.name;
        checksum ^= channel_checksum(info.name, values);
      });
      file.write_attribute<std::int64_t>(attribute(name, "particles"), static_cast<std::int64_t>(p.size()));
      file.write_attribute(attribute(name, "channels"), stored);
      file.write_attribute(attribute(name, "checksum"), Checksum::hex(checksum));
      all.add(name);
      all.add(&checksum, sizeof checksum);
    }
    file.write_attribute("format", std::string(kFormat));
    file.write_attribute("version", kVersion);
    file.write_attribute<std::int32_t>("dim", dim);
    file.write_attribute<std::int32_t>("frame", header.frame);
    file.write_attribute<std::int64_t>("step", header.step);
    file.write_attribute("time", header.time);
    file.write_attribute("dt_previous", header.dt_previous);
    file.write_attribute("scene_digest", header.scene_digest);
    file.write_attribute("run_id", header.run_id);
    file.write_attribute<std::int64_t>("frame_step", header.frame_step);
    file.write_attribute("inputs", inputs_text(header.inputs));
    file.write_attribute("header_checksum", header_checksum(header, dim));
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
  return all.hex();
}

template <int dim>
void load_checkpoint(const std::filesystem::path& path, CheckpointHeader& header, Particles<dim>& into,
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
    throw InputError("checkpoint " + name + " holds a " + std::to_string(stored_dim) + "D scene; this program is " +
                     std::to_string(dim) + "D");

  // Filled locally so that a corrupt file leaves the caller's header untouched.
  CheckpointHeader loaded;
  loaded.dim = stored_dim;
  loaded.frame = file.read_attribute<std::int32_t>("frame");
  loaded.step = file.read_attribute<std::int64_t>("step");
  loaded.time = file.read_attribute<double>("time");
  loaded.dt_previous = file.read_attribute<double>("dt_previous");
  loaded.scene_digest = file.read_string_attribute("scene_digest");
  loaded.run_id = file.read_string_attribute("run_id");
  loaded.frame_step = file.read_attribute<std::int64_t>("frame_step");
  loaded.inputs = parse_inputs(file.read_string_attribute("inputs"), name);
  if (file.has_attribute("stage_data")) {
    for (const std::string& entry : lines(file.read_string_attribute("stage_data"))) {
      const detail::Shape shape = file.shape("stages/" + entry);
      if (shape.size() != 1) throw IoError("checkpoint " + name + " is corrupt: stages/" + entry + " is not 1D");
      std::vector<double> values(shape[0]);
      file.read("stages/" + entry, values.data(), shape);
      loaded.stage_data.emplace_back(entry, std::move(values));
    }
  }
  if (const std::string recorded = file.read_string_attribute("header_checksum"),
      computed = header_checksum(loaded, dim);
      recorded != computed)
    throw IoError("checkpoint " + name + " is corrupt: its header checksum is " + computed + ", the file says " +
                  recorded + " (an attribute was changed after it was written)");

  if (!file.has_attribute(attribute(phase, "channels")))
    throw InputError("checkpoint " + name + " holds no particle phase '" + phase + "'");
  const std::string where = "checkpoint " + name + (phase.empty() ? "" : " phase '" + phase + "'");
  const auto count = file.read_attribute<std::int64_t>(attribute(phase, "particles"));
  if (count < 0) throw IoError(where + " is corrupt: " + std::to_string(count) + " particles");
  const auto n = static_cast<hsize_t>(count);
  const std::vector<std::string> stored = lines(file.read_string_attribute(attribute(phase, "channels")));

  // The file must store exactly the channels the scene's particles keep in checkpoints, each in
  // its shape: checked in full before anything is allocated or read. A derived channel (a cache
  // of others, such as the solid's stress_cache) may be missing, from a checkpoint written
  // before the scene carried it: it is then unknown (NaN) and recomputed by its owner.
  const auto stored_here = [&](const std::string& channel) {
    return std::find(stored.begin(), stored.end(), channel) != stored.end() && file.has(dataset(phase, channel));
  };
  std::vector<std::string> declared;
  into.for_each_channel([&](const ChannelInfo& info, const auto&) {
    if (info.use.checkpoint) declared.push_back(info.name);
  });
  for (const std::string& channel : stored)
    if (std::find(declared.begin(), declared.end(), channel) == declared.end())
      throw InputError(where + " stores the particle channel '" + channel +
                       "', which the scene's particles do not declare (they keep " + joined(declared) +
                       "): it was written by another scene");
  into.for_each_channel([&](const ChannelInfo& info, const auto& values) {
    if (!info.use.checkpoint) return;
    using T = typename std::decay_t<decltype(values)>::value_type;
    const std::string set = dataset(phase, info.name);
    if (!stored_here(info.name)) {
      if (info.use.derived) return;  // loaded as unknown below
      throw InputError(where + " has no particle channel '" + info.name + "' (it stores " + joined(stored) +
                       "): it was written by another scene");
    }
    const detail::Shape expected = shape_of<dim, T>(n), shape = file.shape(set);
    if (shape != expected)
      throw InputError(where + ": particle channel '" + info.name + "' has shape " + describe(shape) + ", expected " +
                       describe(expected) + " (" + Particles<dim>::template type_name<T>() + ")");
  });

  // Read into buffers first, so that `into` stays whole if a read fails; then swapped into
  // place, so that references to its channels stay valid. Particles seeded before the restart
  // are dropped, and channels that checkpoints do not keep start from their initial value.
  using Buffer =
      std::variant<std::vector<double>, std::vector<Vec<dim>>, std::vector<Mat<dim>>, std::vector<std::uint16_t>>;
  std::vector<Buffer> buffers;
  std::uint64_t checksum = 0;
  into.for_each_channel([&](const ChannelInfo& info, const auto& values) {
    if (!info.use.checkpoint) return;
    using T = typename std::decay_t<decltype(values)>::value_type;
    std::vector<T> buffer(n);
    if (stored_here(info.name)) {
      file.read(dataset(phase, info.name), scalars(buffer), shape_of<dim, T>(n));
      checksum ^= channel_checksum(info.name, buffer);
    } else if constexpr (std::is_floating_point_v<T>) {  // derived, not stored: unknown
      std::fill(buffer.begin(), buffer.end(), std::numeric_limits<double>::quiet_NaN());
    } else if constexpr (!std::is_integral_v<T>) {
      for (T& value : buffer) value.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    buffers.emplace_back(std::move(buffer));
  });
  if (const std::string recorded = file.read_string_attribute(attribute(phase, "checksum"));
      recorded != Checksum::hex(checksum))
    throw IoError(where + " is corrupt: the checksum of its particle data is " + Checksum::hex(checksum) +
                  ", the file says " + recorded + " (a dataset was changed after it was written)");
  into.resize(0);
  into.resize(n);
  std::size_t next = 0;
  into.for_each_channel([&](const ChannelInfo& info, auto& values) {
    if (info.use.checkpoint) values.swap(std::get<std::decay_t<decltype(values)>>(buffers[next++]));
  });
  header = std::move(loaded);
}

template std::string save_checkpoint<2>(const std::filesystem::path&, const std::vector<CheckpointPhase<2>>&,
                                        const CheckpointHeader&);
template std::string save_checkpoint<3>(const std::filesystem::path&, const std::vector<CheckpointPhase<3>>&,
                                        const CheckpointHeader&);
template void load_checkpoint<2>(const std::filesystem::path&, CheckpointHeader&, Particles<2>&, const std::string&);
template void load_checkpoint<3>(const std::filesystem::path&, CheckpointHeader&, Particles<3>&, const std::string&);

}  // namespace mpm::io
