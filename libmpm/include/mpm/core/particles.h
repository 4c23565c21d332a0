#pragma once
//! Material points stored as structure-of-arrays: one std::vector per channel.
//!
//! The kinematic channels (x, v, C, mass, volume0, material) exist for every phase and are plain
//! members, so that the hot loops index them directly. Anything else a particle carries is a named
//! extra channel that a library adds at run time (add_channel): the solid's F and plastic state
//! (solid/solid_channels.h), for instance, so a fluid carries no solid fields.
//!
//! for_each_channel is the one list of channels. Growth, reordering, removal, the memory report,
//! the particle frames and the checkpoints all go through it, so a new channel is one add_channel
//! call plus the stage that uses it (docs/architecture.md, "Adding a particle channel").
#include <mpm/core/error.h>
#include <mpm/core/huge_pages.h>
#include <mpm/core/types.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace mpm {

//! Where a channel goes besides memory.
struct ChannelUse {
  bool output = false;      //!< written in particle frames (io/particle_output.h)
  bool checkpoint = false;  //!< stored bit-exactly in checkpoints: every channel that a restart needs
  //! The dataset name in particle frames when it is not the channel's name. Frames hold a matrix
  //! channel as its determinant (ParaView shows scalars and 3-vectors), so "F" is written as "J".
  std::string output_name = {};
  //! A cache of other channels (the solid's stress_cache): a merge of particles
  //! (adaptive/resampling.h) marks it unknown (NaN) instead of averaging it, so that its owner
  //! recomputes it.
  bool derived = false;
};

//! What for_each_channel tells about a channel besides its values.
struct ChannelInfo {
  std::string name;  //!< the field "particle.<name>" of pipelines, the dataset of checkpoints
  ChannelUse use;
  const std::string& frame_name() const { return use.output_name.empty() ? name : use.output_name; }
};

template <int dim>
struct Particles {
  std::vector<Vec<dim>> x;              //!< position [m]
  std::vector<Vec<dim>> v;              //!< velocity [m/s]
  std::vector<Mat<dim>> C;              //!< APIC affine velocity matrix C_p = B_p D_p^-1 [1/s]
  std::vector<double> mass;             //!< [kg]
  std::vector<double> volume0;          //!< reference volume [m^dim]
  std::vector<std::uint16_t> material;  //!< index into the scene's material list

  //! The element types an extra channel may hold.
  template <class T>
  static constexpr bool is_channel_type = std::is_same_v<T, double> || std::is_same_v<T, Vec<dim>> ||
                                          std::is_same_v<T, Mat<dim>> || std::is_same_v<T, std::uint16_t>;

  std::size_t size() const { return x.size(); }
  //! Sum of the particle masses [kg].
  double total_mass() const {
    double m = 0.0;
    for (const double mp : mass) m += mp;
    return m;
  }

  //! Appends one particle at rest (C = 0); every extra channel gets its initial value.
  void push_back(const Vec<dim>& position, const Vec<dim>& velocity, double m, double V0, std::uint16_t mat) {
    const std::size_t p = size();
    resize(p + 1);
    x[p] = position;
    v[p] = velocity;
    mass[p] = m;
    volume0[p] = V0;
    material[p] = mat;
  }

  //! Room for n particles in every channel without reallocation, advised for huge pages
  //! (huge_pages.h): the room is touched first by the particles added next.
  void reserve(std::size_t n) {
    visit_channels(*this, [n](const ChannelInfo&, auto& values, const auto&) {
      if (values.capacity() >= n) return;
      values.reserve(n);
      advise_huge_pages(values.data() + values.size(), (n - values.size()) * sizeof(values[0]));
    });
  }
  //! Room for `more` particles beyond size(), at least doubling the room when it grows (seeding
  //! body after body stays linear).
  void reserve_more(std::size_t more) {
    if (size() + more > capacity()) reserve(std::max(size() + more, 2 * capacity()));
  }
  std::size_t capacity() const { return x.capacity(); }

  //! Sets the number of particles to n, keeping the first min(n, size()). New particles get zero
  //! in the kinematic channels and each extra channel's initial value.
  void resize(std::size_t n) {
    visit_channels(*this, [n](const ChannelInfo&, auto& values, const auto& initial) { values.resize(n, initial); });
  }

  //! Declares the extra channel `name` holding T (double, Vec<dim>, Mat<dim> or std::uint16_t)
  //! and returns it: `initial` for the particles present and for every particle added later.
  //! Idempotent for the same name and type (the first declaration's initial value and use
  //! stay); Error when the name is taken by a channel of another type. The name is letters,
  //! digits and '_' (it becomes a field, an HDF5 dataset and an XDMF attribute). A reference
  //! stays valid when further channels are added.
  template <class T>
  std::vector<T>& add_channel(const std::string& name, const T& initial, ChannelUse use) {
    static_assert(is_channel_type<T>, "a particle channel holds double, Vec<dim>, Mat<dim> or std::uint16_t");
    if (std::vector<T>* existing = find_channel<T>(name)) return *existing;
    if (has_channel(name))
      throw Error("particle channel '" + name + "' exists with type " + type_of(name) + ", not " + type_name<T>());
    if (!is_identifier(name) || !(use.output_name.empty() || is_identifier(use.output_name)))
      throw Error("particle channel '" + name + "' (output name '" + use.output_name +
                  "'): names are letters, digits and '_'");
    if (use.output) {
      const std::string& shown = use.output_name.empty() ? name : use.output_name;
      for_each_channel([&](const ChannelInfo& info, const auto&) {
        if (info.use.output && info.frame_name() == shown)
          throw Error("particle channel '" + name + "': channel '" + info.name + "' is written to frames as '" + shown +
                      "' already");
      });
    }
    Extra& extra =
        extras_.emplace_back(Extra{{name, std::move(use)}, Column<T>{std::vector<T>(size(), initial), initial}});
    return std::get<Column<T>>(extra.column).values;
  }

  //! The channel `name` holding T; Error naming it and the channels present when there is none.
  template <class T>
  std::vector<T>& channel(const std::string& name) {
    if (std::vector<T>* found = find_channel<T>(name)) return *found;
    throw Error(missing(name, type_name<T>()));
  }
  template <class T>
  const std::vector<T>& channel(const std::string& name) const {
    if (const std::vector<T>* found = find_channel<T>(name)) return *found;
    throw Error(missing(name, type_name<T>()));
  }
  //! The channel `name` holding T, or nullptr.
  template <class T>
  std::vector<T>* find_channel(const std::string& name) {
    return find<T>(*this, name);
  }
  template <class T>
  const std::vector<T>* find_channel(const std::string& name) const {
    return find<T>(*this, name);
  }
  bool has_channel(const std::string& name) const {
    bool found = false;
    for_each_channel([&](const ChannelInfo& info, const auto&) { found = found || info.name == name; });
    return found;
  }

  //! Calls visit(const ChannelInfo&, std::vector<T>&) for every channel: the kinematic ones in
  //! the order of their members, then the extra ones in the order they were added.
  template <class Visitor>
  void for_each_channel(Visitor&& visit) {
    visit_channels(*this, [&](const ChannelInfo& info, auto& values, const auto&) { visit(info, values); });
  }
  template <class Visitor>
  void for_each_channel(Visitor&& visit) const {
    visit_channels(*this, [&](const ChannelInfo& info, const auto& values, const auto&) { visit(info, values); });
  }

  //! Reorders every channel so that new index i holds old index order[i]; an `order` shorter
  //! than size() keeps only the particles it lists.
  void permute(const std::vector<std::uint32_t>& order) {
    // One buffer per element type: each channel's old storage, swapped out, receives the next
    // channel of its type, so a move allocates (and the kernel first-touches) one array per
    // type instead of one per channel.
    std::tuple<std::vector<double>, std::vector<Vec<dim>>, std::vector<Mat<dim>>, std::vector<std::uint16_t>> spare;
    for_each_channel([&](const ChannelInfo&, auto& values) {
      apply_permutation(values, order, std::get<std::decay_t<decltype(values)>>(spare));
    });
  }

  //! Removes every particle p with flagged[p] != 0 (flagged.size() == size()) from every
  //! channel; the others keep their order (stable). O(N): one scan for the kept indices, then
  //! the parallel gather of permute(). Returns the number removed.
  std::size_t erase_flagged(const std::vector<std::uint8_t>& flagged) {
    std::vector<std::uint32_t> kept;
    kept.reserve(size());
    for (std::size_t p = 0; p < size(); ++p)
      if (!flagged[p]) kept.push_back(static_cast<std::uint32_t>(p));
    const std::size_t removed = size() - kept.size();
    if (removed > 0) permute(kept);
    return removed;
  }

  //! Bytes held per channel ("particle.<name>"), for the memory report of a run.
  std::vector<std::pair<std::string, std::size_t>> memory_per_field() const {
    std::vector<std::pair<std::string, std::size_t>> bytes;
    for_each_channel([&](const ChannelInfo& info, const auto& values) {
      using T = typename std::decay_t<decltype(values)>::value_type;
      bytes.emplace_back("particle." + info.name, values.capacity() * sizeof(T));
    });
    return bytes;
  }

  //! "double", "Vec<2>", "Mat<3>" or "uint16": the element type T in messages.
  template <class T>
  static std::string type_name() {
    static_assert(is_channel_type<T>, "a particle channel holds double, Vec<dim>, Mat<dim> or std::uint16_t");
    if constexpr (std::is_same_v<T, double>)
      return "double";
    else if constexpr (std::is_same_v<T, Vec<dim>>)
      return "Vec<" + std::to_string(dim) + ">";
    else if constexpr (std::is_same_v<T, Mat<dim>>)
      return "Mat<" + std::to_string(dim) + ">";
    else
      return "uint16";
  }

private:
  template <class T>
  struct Column {
    std::vector<T> values;
    T initial;
  };
  struct Extra {
    ChannelInfo info;
    std::variant<Column<double>, Column<Vec<dim>>, Column<Mat<dim>>, Column<std::uint16_t>> column;
  };
  //! A deque keeps references to its elements when it grows, so a channel that a caller holds
  //! stays valid when another library adds one; and it keeps Particles copyable.
  std::deque<Extra> extras_;

  //! THE list of channels. Calls visit(info, values, initial) for every channel; `initial` is
  //! what resize() gives new particles (zero for the kinematic channels). Self is Particles or
  //! const Particles.
  template <class Self, class Visitor>
  static void visit_channels(Self& self, Visitor&& visit) {
    // Frames show x as the points' geometry "position" and v as "velocity", the names ParaView
    // users know; C only serves to continue a run.
    static const std::array<ChannelInfo, 6> kinematic{{{"x", {true, true, "position"}},
                                                       {"v", {true, true, "velocity"}},
                                                       {"C", {false, true}},
                                                       {"mass", {true, true}},
                                                       {"volume0", {true, true}},
                                                       {"material", {true, true}}}};
    visit(kinematic[0], self.x, Vec<dim>(Vec<dim>::Zero()));
    visit(kinematic[1], self.v, Vec<dim>(Vec<dim>::Zero()));
    visit(kinematic[2], self.C, Mat<dim>(Mat<dim>::Zero()));
    visit(kinematic[3], self.mass, 0.0);
    visit(kinematic[4], self.volume0, 0.0);
    visit(kinematic[5], self.material, std::uint16_t{0});
    for (auto& extra : self.extras_)
      std::visit([&](auto& column) { visit(std::as_const(extra.info), column.values, std::as_const(column.initial)); },
                 extra.column);
  }

  template <class T, class Self>
  static auto find(Self& self, const std::string& name) {
    static_assert(is_channel_type<T>, "a particle channel holds double, Vec<dim>, Mat<dim> or std::uint16_t");
    using Found = std::conditional_t<std::is_const_v<Self>, const std::vector<T>*, std::vector<T>*>;
    Found found = nullptr;
    visit_channels(self, [&](const ChannelInfo& info, auto& values, const auto&) {
      if constexpr (std::is_same_v<typename std::decay_t<decltype(values)>::value_type, T>)
        if (info.name == name) found = &values;
    });
    return found;
  }

  //! The type name of the channel `name` ("" when there is none).
  std::string type_of(const std::string& name) const {
    std::string type;
    for_each_channel([&](const ChannelInfo& info, const auto& values) {
      if (info.name == name) type = type_name<typename std::decay_t<decltype(values)>::value_type>();
    });
    return type;
  }

  std::string missing(const std::string& name, const std::string& type) const {
    std::string present;
    for_each_channel(
        [&](const ChannelInfo& info, const auto&) { present += (present.empty() ? "" : ", ") + info.name; });
    const std::string other = type_of(name);
    return "particles have no channel '" + name + "' of type " + type +
           (other.empty() ? "" : " (it holds " + other + ")") + "; channels: " + present;
  }

  static bool is_identifier(const std::string& name) {
    if (name.empty()) return false;
    for (const char c : name)
      if (!(c == '_' || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'))) return false;
    return true;
  }

  //! A parallel gather: the reads are random when the order is scattered, so the memory
  //! latency of both cores overlaps (bench_transfer, shuffled input).
  template <class T>
  static void apply_permutation(std::vector<T>& a, const std::vector<std::uint32_t>& order, std::vector<T>& out) {
    reserve_advised(out, order.size());
    out.resize(order.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 8192), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = a[order[i]];
    });
    a.swap(out);
  }
};

//! The fields "particle.<name>" of every channel of P: what a scene provides before the first
//! stage runs (core/pipeline.h), so that a stage reading a channel the particles lack (say
//! "particle.F" without the solid channels) fails when the pipeline is assembled.
template <int dim>
std::vector<std::string> particle_fields(const Particles<dim>& P) {
  std::vector<std::string> fields;
  P.for_each_channel([&](const ChannelInfo& info, const auto&) { fields.push_back("particle." + info.name); });
  return fields;
}

}  // namespace mpm
