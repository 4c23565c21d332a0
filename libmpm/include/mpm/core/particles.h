#pragma once
//! Material points stored as structure-of-arrays.
//!
//! The kinematic channels (x, v, C, mass, volume0, material) exist for every phase. The
//! deformation channels (F, plastic) are empty unless a stage that needs them allocates them,
//! so a fluid-only scene carries no solid fields. Every non-empty channel has size().
#include <mpm/core/types.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace mpm {

template <int dim>
struct Particles {
  std::vector<Vec<dim>> x;            //!< position [m]
  std::vector<Vec<dim>> v;            //!< velocity [m/s]
  std::vector<Mat<dim>> C;            //!< APIC affine velocity matrix C_p = B_p D_p^-1 [1/s]
  std::vector<double> mass;           //!< [kg]
  std::vector<double> volume0;        //!< reference volume [m^dim]
  std::vector<std::uint16_t> material;//!< index into the scene's material list
  std::vector<Mat<dim>> F;            //!< elastic deformation gradient F^E (solid only)
  std::vector<double> plastic;        //!< plastic state: log volume correction (Tampubolon 2017) (solid only)

  std::size_t size() const { return x.size(); }
  //! Sum of the particle masses [kg].
  double total_mass() const {
    double m = 0.0;
    for (const double mp : mass) m += mp;
    return m;
  }
  bool has_deformation() const { return deformation_; }

  //! Appends one particle at rest with identity deformation (when deformation is tracked).
  void push_back(const Vec<dim>& position, const Vec<dim>& velocity, double m, double V0,
                 std::uint16_t mat) {
    x.push_back(position);
    v.push_back(velocity);
    C.push_back(Mat<dim>::Zero());
    mass.push_back(m);
    volume0.push_back(V0);
    material.push_back(mat);
    if (has_deformation()) {
      F.push_back(Mat<dim>::Identity());
      plastic.push_back(0.0);
    }
  }

  //! Tracks F and the plastic state from now on: F = I and plastic = 0 for the particles
  //! present and for every particle added later (idempotent).
  void enable_deformation() {
    if (deformation_) return;
    deformation_ = true;
    F.assign(size(), Mat<dim>::Identity());
    plastic.assign(size(), 0.0);
  }

  //! Reorders every non-empty channel so that new index i holds old index order[i]; an
  //! `order` shorter than size() keeps only the particles it lists.
  void permute(const std::vector<std::uint32_t>& order) {
    apply_permutation(x, order);
    apply_permutation(v, order);
    apply_permutation(C, order);
    apply_permutation(mass, order);
    apply_permutation(volume0, order);
    apply_permutation(material, order);
    apply_permutation(F, order);
    apply_permutation(plastic, order);
  }

  //! Removes every particle p with flagged[p] != 0 (flagged.size() == size()) from every
  //! non-empty channel; the others keep their order (stable). O(N): one scan for the kept
  //! indices, then the parallel gather of permute(). Returns the number removed.
  std::size_t erase_flagged(const std::vector<std::uint8_t>& flagged) {
    std::vector<std::uint32_t> kept;
    kept.reserve(size());
    for (std::size_t p = 0; p < size(); ++p)
      if (!flagged[p]) kept.push_back(static_cast<std::uint32_t>(p));
    const std::size_t removed = size() - kept.size();
    if (removed > 0) permute(kept);
    return removed;
  }

  //! Bytes held per channel, for the memory report of a run.
  std::vector<std::pair<std::string, std::size_t>> memory_per_field() const {
    return {{"particle.x", bytes(x)},         {"particle.v", bytes(v)},
            {"particle.C", bytes(C)},         {"particle.mass", bytes(mass)},
            {"particle.volume0", bytes(volume0)}, {"particle.material", bytes(material)},
            {"particle.F", bytes(F)},         {"particle.plastic", bytes(plastic)}};
  }

private:
  bool deformation_ = false;

  template <class T>
  static std::size_t bytes(const std::vector<T>& a) { return a.capacity() * sizeof(T); }

  //! A parallel gather: the reads are random when the order is scattered, so the memory
  //! latency of both cores overlaps (bench_transfer, shuffled input).
  template <class T>
  static void apply_permutation(std::vector<T>& a, const std::vector<std::uint32_t>& order) {
    if (a.empty()) return;
    std::vector<T> out(order.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 8192), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = a[order[i]];
    });
    a.swap(out);
  }
};

}  // namespace mpm
