#include <coupling/bed_load.h>
#include <mpm/core/error.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace coupling {

namespace {
//! The column id of node coordinates c (bed_column's numbering).
template <int dim>
std::int64_t column_id(const mpm::IVec<dim>& counts, int up, const mpm::IVec<dim>& c) {
  std::int64_t id = 0;
  for (int a = dim - 1; a >= 0; --a)
    if (a != up) id = id * counts[a] + c[a];
  return id;
}
}  // namespace

bool BedLoadLaw::in_log_layer(double depth) const { return 11.0 * depth > std::exp(1.0) * roughness * grain_diameter; }

double BedLoadLaw::friction_velocity(double speed, double depth) const {
  mpm::verify<mpm::Error>(in_log_layer(depth), "bed load: a water depth within the roughness height");
  return von_karman * speed / std::log(11.0 * depth / (roughness * grain_diameter));
}

double BedLoadLaw::suspending_stress(double settling_velocity, double rouse_number) const {
  const double u_star = settling_velocity / (von_karman * rouse_number);
  return fluid_density * u_star * u_star;
}

double BedLoadLaw::shields_number(double friction_velocity) const {
  return fluid_density * friction_velocity * friction_velocity /
         ((sediment_density - fluid_density) * gravity * grain_diameter);
}

double BedLoadLaw::saltation_length(double shields) const {
  if (!(shields > critical_shields)) return 0.0;
  const double nu = fluid_viscosity / fluid_density;
  const double particle_parameter =
      grain_diameter * std::cbrt((sediment_density / fluid_density - 1.0) * gravity / (nu * nu));
  const double stage = (shields - critical_shields) / critical_shields;
  return 3.0 * grain_diameter * std::pow(particle_parameter, 0.6) * std::pow(stage, 0.9);
}

double BedLoadLaw::flux(double shields) const {
  if (!(shields > critical_shields)) return 0.0;
  const double s = sediment_density / fluid_density;
  return coefficient * std::pow(shields - critical_shields, exponent) *
         std::sqrt((s - 1.0) * gravity * grain_diameter * grain_diameter * grain_diameter);
}

template <int dim>
std::int64_t bed_column(const mpm::SparseGrid<dim>& grid, int up, const mpm::Vec<dim>& x) {
  const mpm::IVec<dim> c = ((x - grid.origin()) / grid.dx()).array().round().template cast<int>();
  if ((c.array() < 0).any() || (c.array() >= grid.node_counts().array()).any()) return -1;
  return column_id(grid.node_counts(), up, c);
}

template <int dim>
void find_bed_layer(const BedLoadLaw& law, int up, const mpm::SparseGrid<dim>& fluid,
                    const mpm::SparseGrid<dim>& sediment, const VolumeFractions& fractions,
                    const mpm::geometry::ColliderSet<dim>& obstacles, double time, BedLayer<dim>& layer) {
  mpm::verify<mpm::Error>(fractions.sediment.size() == sediment.node_storage(),
                          "bed load: no volume fractions of this step");
  const mpm::IVec<dim>& counts = sediment.node_counts();
  const auto column_of = [&](const mpm::IVec<dim>& c) { return column_id(counts, up, c); };
  std::int64_t columns = 1;
  for (int a = 0; a < dim; ++a)
    if (a != up) columns *= counts[a];
  // The surface node of each column: its highest node of n_s >= the surface fraction that no
  // obstacle prescribes (the sand below a pipe resting on the bed reaches nodes inside it).
  std::vector<mpm::IVec<dim>> top(static_cast<std::size_t>(columns), mpm::IVec<dim>::Constant(-1));
  for (std::size_t k = 0; k < sediment.node_storage(); ++k) {
    if (!(sediment.mass[k] > 0.0) || fractions.sediment[k] < law.surface_fraction) continue;
    const mpm::IVec<dim> c = sediment.node_coord(k);
    // Allocated blocks reach past the domain's last node; such nodes have no column.
    if ((c.array() >= counts.array()).any()) continue;
    mpm::IVec<dim>& t = top[static_cast<std::size_t>(column_of(c))];
    // The obstacles are asked only about a node that would become the top.
    if (c[up] > t[up] && !obstacles.prescribes(sediment.node_position(k), time)) t = c;
  }

  layer.up = up;
  layer.nodes.clear();
  layer.stress.assign(top.size(), mpm::Vec<dim>::Zero());
  layer.drift.assign(top.size(), mpm::Vec<dim>::Zero());
  layer.flux.assign(top.size(), mpm::Vec<dim>::Zero());
  // Per column: the formula's flux q_e and the current's direction (zero: no transport), the step
  // length, the layer's sediment mass and the water's speed over the bed.
  std::vector<mpm::Vec<dim>> direction(top.size(), mpm::Vec<dim>::Zero());
  std::vector<double> capacity(top.size(), 0.0), length = capacity, layer_mass = capacity, water_speed = capacity;
  layer.largest_shields = 0.0;
  const double dx = sediment.dx(), width = std::pow(dx, dim - 1);
  const mpm::IVec<dim> step = mpm::IVec<dim>::Unit(up);
  for (std::size_t col = 0; col < top.size(); ++col) {
    if (top[col][up] < 0) continue;
    double mass = 0.0, n_s[2] = {0.0, 0.0};
    const std::size_t surface = layer.nodes.size();  // the surface node's entry (it has mass)
    for (int j = 0; j < 2; ++j) {
      const mpm::IVec<dim> c = top[col] + j * step;
      const mpm::Index ks = sediment.node_index(c);
      if (ks < 0 || !(sediment.mass[static_cast<std::size_t>(ks)] > 0.0)) continue;
      const mpm::Index kw = fluid.node_index(c);
      BedLayerNode<dim> node;
      node.sediment = static_cast<std::size_t>(ks);
      node.fluid = kw >= 0 && fluid.mass[static_cast<std::size_t>(kw)] > 0.0 ? kw : -1;
      node.column = static_cast<std::int64_t>(col);
      node.v_s = sediment.velocity[node.sediment];
      if (node.fluid >= 0) node.v_w = fluid.velocity[static_cast<std::size_t>(node.fluid)];
      layer.nodes.push_back(node);
      mass += sediment.mass[node.sediment];
      n_s[j] = fractions.sediment[node.sediment];
    }
    // The water column above the bed: the nodes from the one above the surface node up to the
    // first without water (the free surface) or inside an obstacle (below a pipe: the gap; P2G
    // gives water to the nodes up to 1.5 dx inside the pipe, whose velocities the pipe sets).
    double water = 0.0;
    mpm::Vec<dim> momentum = mpm::Vec<dim>::Zero();
    for (int j = 1;; ++j) {
      const mpm::Index kw = fluid.node_index(top[col] + j * step);
      if (kw < 0 || !(fluid.mass[static_cast<std::size_t>(kw)] > 0.0) ||
          obstacles.prescribes(fluid.node_position(static_cast<std::size_t>(kw)), time))
        break;
      water += fluid.mass[static_cast<std::size_t>(kw)];
      momentum += fluid.mass[static_cast<std::size_t>(kw)] * fluid.velocity[static_cast<std::size_t>(kw)];
    }
    if (!(water > 0.0)) continue;
    mpm::Vec<dim> u = momentum / water - layer.nodes[surface].v_s;
    u[up] = 0.0;
    const double speed = u.norm();
    // The bed level between the surface node and the node above, where n_s crosses the surface
    // fraction (n_s[0] >= it > n_s[1]). The nodes from the one above count the water from half a
    // spacing above the surface node.
    const double crossing = std::clamp((n_s[0] - law.surface_fraction) / (n_s[0] - n_s[1]), 0.0, 1.0);
    const double depth = water / (law.fluid_density * width) + (0.5 - crossing) * dx;
    if (!(speed > 0.0) || !law.in_log_layer(depth)) continue;
    const double u_star = law.friction_velocity(speed, depth);
    const double theta = law.shields_number(u_star);
    layer.largest_shields = std::max(layer.largest_shields, theta);
    const mpm::Vec<dim> along = u / speed;
    layer.stress[col] = law.fluid_density * u_star * u_star * along;
    if (!(mass > 0.0)) continue;
    capacity[col] = law.morphological_factor * law.flux(theta);
    direction[col] = along;
    length[col] = law.step_length_at(theta);
    layer_mass[col] = mass;
    water_speed[col] = speed;
    layer.flux[col] = capacity[col] * along;
  }
  if (law.picks_up()) {
    const std::vector<mpm::Vec<dim>> formula = layer.flux;
    relax_to_capacity(counts, up, dx, formula, direction, length, layer.flux);
  }
  // The drift that carries each column's flux in the layer's grains, at most the water's speed.
  for (std::size_t col = 0; col < top.size(); ++col) {
    const double q = law.picks_up() ? layer.flux[col].norm() : capacity[col];
    if (!(q > 0.0)) continue;
    const mpm::Vec<dim> along = law.picks_up() ? (layer.flux[col] / q).eval() : direction[col];
    layer.drift[col] = std::min(law.sediment_density * q * width / layer_mass[col], water_speed[col]) * along;
  }
}

template <int dim>
int relax_to_capacity(const mpm::IVec<dim>& counts, int up, double dx, const std::vector<mpm::Vec<dim>>& capacity,
                      const std::vector<mpm::Vec<dim>>& direction, const std::vector<double>& length,
                      std::vector<mpm::Vec<dim>>& flux, int max_sweeps) {
  // The columns' lattice: the horizontal axes, the first the fastest (as find_bed_layer numbers them).
  std::array<int, dim - 1> axes{};
  std::array<std::int64_t, dim - 1> size{}, stride{};
  std::int64_t columns = 1;
  for (int a = 0, h = 0; a < dim; ++a) {
    if (a == up) continue;
    axes[h] = a;
    size[h] = counts[a];
    stride[h] = columns;
    columns *= counts[a];
    ++h;
  }
  mpm::verify<mpm::Error>(capacity.size() == std::size_t(columns) && direction.size() == capacity.size() &&
                              length.size() == capacity.size(),
                          "bed load: one capacity, direction and step length per column");
  flux.assign(capacity.size(), mpm::Vec<dim>::Zero());
  double scale = 0.0;
  for (const mpm::Vec<dim>& q : capacity) scale = std::max(scale, q.norm());
  if (!(scale > 0.0)) return 0;
  // One column's update from its upwind neighbours' current fluxes (its lattice coordinates i);
  // returns its change.
  const auto update = [&](std::int64_t col, const std::array<std::int64_t, dim - 1>& i) {
    const mpm::Vec<dim>& e = direction[std::size_t(col)];
    if (e.squaredNorm() == 0.0) return 0.0;
    const double c = length[std::size_t(col)] / dx;
    mpm::Vec<dim> sum = capacity[std::size_t(col)];
    double diagonal = 1.0;
    for (int h = 0; h < dim - 1; ++h) {
      const double w = c * std::abs(e[axes[h]]);
      if (w == 0.0) continue;
      diagonal += w;
      const std::int64_t upwind = e[axes[h]] > 0.0 ? i[h] - 1 : i[h] + 1;
      if (upwind >= 0 && upwind < size[h]) sum += w * flux[std::size_t(col + (upwind - i[h]) * stride[h])];
    }
    const mpm::Vec<dim> q = sum / diagonal;
    const double change = (q - flux[std::size_t(col)]).norm();
    flux[std::size_t(col)] = q;
    return change;
  };
  // Sweep orders: each horizontal axis forwards or backwards (in 2D: left to right, right to left).
  constexpr int orders = 1 << (dim - 1);
  for (int sweep = 1; sweep <= max_sweeps; ++sweep) {
    const int order = (sweep - 1) % orders;
    double change = 0.0;
    for (std::int64_t k = 0; k < columns; ++k) {
      std::array<std::int64_t, dim - 1> i{};
      std::int64_t col = 0, rest = k;
      for (int h = dim - 2; h >= 0; --h) {
        i[h] = rest / stride[h];
        rest -= i[h] * stride[h];
        if (order & (1 << h)) i[h] = size[h] - 1 - i[h];
        col += i[h] * stride[h];
      }
      change = std::max(change, update(col, i));
    }
    // Converged once a whole cycle of orders changed nothing beyond round-off.
    if (change <= 1e-14 * scale && sweep >= orders) return sweep;
  }
  return max_sweeps;
}

template <int dim>
std::size_t limit_bed_shear(const BedLayer<dim>& layer, mpm::SparseGrid<dim>& fluid, mpm::SparseGrid<dim>& sediment,
                            double dt) {
  const double width = std::pow(sediment.dx(), dim - 1);
  const auto tangential = [&](mpm::Vec<dim> v) {
    v[layer.up] = 0.0;
    return v;
  };
  std::size_t limited = 0;
  // The nodes of a column are consecutive (find_bed_layer).
  for (std::size_t first = 0, last = 0; first < layer.nodes.size(); first = last) {
    const std::int64_t col = layer.nodes[first].column;
    mpm::Vec<dim> impulse = mpm::Vec<dim>::Zero();
    for (last = first; last < layer.nodes.size() && layer.nodes[last].column == col; ++last) {
      const BedLayerNode<dim>& n = layer.nodes[last];
      impulse += sediment.mass[n.sediment] * tangential(sediment.velocity[n.sediment] - n.v_s);
    }
    const double allowed = layer.stress[static_cast<std::size_t>(col)].norm() * width * dt;
    if (!(impulse.norm() > allowed)) continue;
    ++limited;
    // Each node's exchange moved m_w dv_w = -m_s dv_s: scaling both keeps its momentum.
    const double f = allowed / impulse.norm();
    for (std::size_t i = first; i < last; ++i) {
      const BedLayerNode<dim>& n = layer.nodes[i];
      for (int a = 0; a < dim; ++a) {
        if (a == layer.up) continue;
        double& v_s = sediment.velocity[n.sediment][a];
        v_s = n.v_s[a] + f * (v_s - n.v_s[a]);
        if (n.fluid < 0) continue;
        double& v_w = fluid.velocity[static_cast<std::size_t>(n.fluid)][a];
        v_w = n.v_w[a] + f * (v_w - n.v_w[a]);
      }
    }
  }
  return limited;
}

#define BED_LOAD(dim)                                                                                               \
  template void find_bed_layer(const BedLoadLaw&, int, const mpm::SparseGrid<dim>&, const mpm::SparseGrid<dim>&,    \
                               const VolumeFractions&, const mpm::geometry::ColliderSet<dim>&, double,              \
                               BedLayer<dim>&);                                                                     \
  template std::size_t limit_bed_shear(const BedLayer<dim>&, mpm::SparseGrid<dim>&, mpm::SparseGrid<dim>&, double); \
  template int relax_to_capacity(const mpm::IVec<dim>&, int, double, const std::vector<mpm::Vec<dim>>&,             \
                                 const std::vector<mpm::Vec<dim>>&, const std::vector<double>&,                     \
                                 std::vector<mpm::Vec<dim>>&, int);                                                 \
  template std::int64_t bed_column(const mpm::SparseGrid<dim>&, int, const mpm::Vec<dim>&);
BED_LOAD(2)
BED_LOAD(3)

}  // namespace coupling
