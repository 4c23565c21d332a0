#include <mpm/core/error.h>
#include <mpm/core/sparse_grid.h>

#include <algorithm>
#include <cmath>

namespace mpm {

template <int dim>
SparseGrid<dim>::SparseGrid(const Vec<dim>& lo, const Vec<dim>& hi, double dx, const std::array<bool, dim>& periodic)
    : dx_(dx), origin_(lo) {
  verify<InputError>(dx > 0.0 && std::isfinite(dx), "grid spacing dx must be > 0");
  for (int a = 0; a < dim; ++a) {
    verify<InputError>(hi[a] > lo[a], "grid domain must have hi > lo on every axis");
    node_counts_[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / dx - 1e-9)) + 1;
    if (periodic[a]) {
      const double cells = (hi[a] - lo[a]) / dx;
      period_[a] = static_cast<int>(std::lround(cells));
      verify<InputError>(
          period_[a] >= 2 && std::abs(cells - period_[a]) <= 1e-9 * cells,
          "a periodic axis needs a whole number (>= 2) of cells: (hi - lo) / dx = " + std::to_string(cells));
      origin_[a] -= periodic_margin * dx;
      node_counts_[a] = period_[a] + 1 + 2 * periodic_margin;
    }
    block_counts_[a] = (node_counts_[a] + block_size - 1) / block_size + 1;
    verify<InputError>(block_counts_[a] < (1 << std::min(key_bits, 30)),
                       "grid too large: " + std::to_string(node_counts_[a]) + " nodes on axis " + std::to_string(a) +
                           " (domain / dx); at most " +
                           std::to_string(static_cast<long long>(block_size) << std::min(key_bits, 30)) + " in " +
                           std::to_string(dim) + "D");
  }
  slot_.reset(0);
}

template <int dim>
void SparseGrid<dim>::activate(const std::vector<BlockKey>& block_ids) {
  active_ = block_ids;
  if (is_periodic()) {
    const IVec<dim> lo = periodic_lo(), hi = lo + period_;
    for (BlockKey id : block_ids) {
      const IVec<dim> first = block_coord(id) * block_size;
      const IVec<dim> last = first + IVec<dim>::Constant(block_size - 1);
      bool ghost = false;
      for (int a = 0; a < dim; ++a) ghost = ghost || (period_[a] > 0 && (first[a] < lo[a] || last[a] >= hi[a]));
      if (!ghost) continue;
      for (int local = 0; local < nodes_per_block; ++local) {
        IVec<dim> node;
        for (int a = 0; a < dim; ++a) node[a] = first[a] + ((local >> (a * block_bits)) & (block_size - 1));
        const IVec<dim> image = periodic_image(node);
        if (image != node) active_.push_back(block_id(image));
      }
    }
    std::sort(active_.begin(), active_.end());
    active_.erase(std::unique(active_.begin(), active_.end()), active_.end());
  }
  slot_.reset(active_.size());
  for (std::size_t s = 0; s < active_.size(); ++s) slot_.insert(active_[s], static_cast<int>(s));
  const std::size_t n = active_.size() * nodes_per_block;
  mass.assign(n, 0.0);
  velocity.assign(n, Vec<dim>::Zero());
}

template <int dim>
IVec<dim> SparseGrid<dim>::node_coord(std::size_t k) const {
  const IVec<dim> block = block_coord(active_[k / nodes_per_block]);
  int local = static_cast<int>(k % nodes_per_block);
  IVec<dim> c;
  for (int a = 0; a < dim; ++a) {
    c[a] = (block[a] << block_bits) + (local & (block_size - 1));
    local >>= block_bits;
  }
  return c;
}

template <int dim>
Index SparseGrid<dim>::node_index(const IVec<dim>& node) const {
  for (int a = 0; a < dim; ++a)
    if (node[a] < 0 || (node[a] >> block_bits) >= block_counts_[a]) return -1;
  const int s = slot_.find(block_id(node));
  if (s < 0) return -1;
  return static_cast<Index>(s) * nodes_per_block + local_index(node);
}

template <int dim>
std::vector<std::pair<std::string, std::size_t>> SparseGrid<dim>::memory_per_field() const {
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  return {{"grid.block_table", slot_.bytes() + active_.capacity() * sizeof(BlockKey)},
          {"grid.mass", bytes(mass)},
          {"grid.velocity", bytes(velocity)},
          {"grid.velocity_old", bytes(velocity_old)},
          {"grid.force", bytes(force)}};
}

template <int dim>
std::size_t SparseGrid<dim>::memory_bytes() const {
  std::size_t total = 0;
  for (const auto& [name, bytes] : memory_per_field()) total += bytes;
  return total;
}

template class SparseGrid<2>;
template class SparseGrid<3>;

}  // namespace mpm
