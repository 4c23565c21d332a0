// Velocity extension to the loose surface nodes (surface_velocity_extension.h):
//   reached: the corners of the fluid cells (fluid_cell.h, the projection's rule) and the nodes
//            a wall or collider holds (their velocity is boundary data);
//   loose:   canonical nodes with mass that are neither, among them the nodes slipping along
//            an obstacle deeper inside it than the fluid cells' corners (the pressure reaches
//            none of them: in a tank at rest with slip walls they would fall freely and hand
//            the particles beside the wall a share of g every step);
//   layer l: every loose node with a reached neighbour (3^dim box, wrapped on periodic axes)
//            takes their mean velocity (a slipping node: its part in the directions the
//            obstacles leave free; it keeps the held ones) and counts as reached from layer
//            l + 1 on.
// A kernel of radius r cells leaves loose nodes at most ceil(r) layers out; the loop stops when a
// layer is empty (a loose node with no reached node near it keeps v*).
#include <fluid/stages/prescribed_nodes.h>
#include <fluid/stages/surface_velocity_extension.h>

#include "fluid_cell.h"

#include <tbb/parallel_for.h>

#include <atomic>

namespace fluid::stages {

namespace {
enum : std::uint8_t { kLoose = 0, kReached = 1, kLeftAlone = 2, kPrescribed = 3 };
}

template <int dim>
void SurfaceVelocityExtension<dim>::run(mpm::MpmState<dim>& s) {
  mpm::SparseGrid<dim>& g = s.grid;
  const std::size_t nodes = g.node_storage();
  extended_ = 0;
  // Reached corners, marked in parallel (every writer stores the same byte); the particles are
  // sorted, so a run of them in one cell marks it once.
  state_.assign(nodes, kLoose);
  const auto& X = s.particles.x;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, X.size(), 4096), [&](const auto& r) {
    mpm::IVec<dim> last = mpm::IVec<dim>::Constant(-1);
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const mpm::IVec<dim> c = fluid_cell_of(g, X[p]);
      if (c == last) continue;
      last = c;
      for (int corner = 0; corner < (1 << dim); ++corner) {
        mpm::IVec<dim> n = c;
        for (int a = 0; a < dim; ++a) n[a] += (corner >> a) & 1;
        if (const mpm::Index k = g.node_index(g.periodic_image(n)); k >= 0)
          std::atomic_ref<std::uint8_t>(state_[k]).store(kReached, std::memory_order_relaxed);
      }
    }
  });
  // Loose: the other canonical nodes with mass (the ghosts of periodic axes get their canonical
  // node's velocity from periodic_fill) whose velocity no wall prescribes (those are reached).
  const bool periodic = g.is_periodic();
  const double t = s.time + s.dt;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes, 1024), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      if (state_[k] == kReached) continue;
      if (!(g.mass[k] > 0.0) || (periodic && g.periodic_image(g.node_coord(k)) != g.node_coord(k)))
        state_[k] = kLeftAlone;
      else if (is_prescribed(g, colliders_, k, t))
        state_[k] = kPrescribed;
    }
  });
  // A prescribed node is loose in the directions the obstacles leave free (few nodes: serial).
  std::vector<mpm::Index> loose;
  slip_index_.assign(nodes, -1);
  slip_projector_.clear();
  for (std::size_t k = 0; k < nodes; ++k) {
    if (state_[k] == kPrescribed) {
      const std::optional<mpm::Mat<dim>> free = slip_directions(colliders_, g.node_position(k), t);
      state_[k] = free ? kLoose : kReached;
      if (free) {
        slip_index_[k] = static_cast<std::int32_t>(slip_projector_.size());
        slip_projector_.push_back(*free);
      }
    }
    if (state_[k] == kLoose) loose.push_back(static_cast<mpm::Index>(k));
  }

  while (!loose.empty()) {
    layer_.clear();
    extended_velocity_.clear();
    std::size_t kept = 0;
    for (const mpm::Index k : loose) {
      const mpm::IVec<dim> n = g.node_coord(static_cast<std::size_t>(k));
      mpm::Vec<dim> sum = mpm::Vec<dim>::Zero();
      int count = 0;
      mpm::IVec<dim> o = mpm::IVec<dim>::Constant(-1);
      for (int m = 0; m < mpm::ipow(3, dim); ++m) {
        const mpm::Index j = g.node_index(g.periodic_image(n + o));
        if (j >= 0 && state_[j] == kReached) {
          sum += g.velocity[j];
          ++count;
        }
        for (int a = 0; a < dim; ++a) {
          if (++o[a] <= 1) break;
          o[a] = -1;
        }
      }
      if (count == 0) {
        loose[kept++] = k;
        continue;
      }
      mpm::Vec<dim> extended = sum / count;
      if (const std::int32_t j = slip_index_[static_cast<std::size_t>(k)]; j >= 0) {
        const mpm::Mat<dim>& free = slip_projector_[static_cast<std::size_t>(j)];
        extended = free * extended + (mpm::Mat<dim>::Identity() - free) * g.velocity[k];
      }
      layer_.push_back(k);
      extended_velocity_.push_back(extended);
    }
    if (layer_.empty()) break;
    for (std::size_t i = 0; i < layer_.size(); ++i) {
      g.velocity[layer_[i]] = extended_velocity_[i];
      state_[layer_[i]] = kReached;
    }
    extended_ += static_cast<std::int64_t>(layer_.size());
    loose.resize(kept);
  }
}

template class SurfaceVelocityExtension<2>;
template class SurfaceVelocityExtension<3>;

}  // namespace fluid::stages
