// Particle resampling (resampling.h): surface distance on the finest cells, split and merge
// candidates by the distance bands, count guards, then the merges in place, the splits
// appended, the merged-away particles erased.
#include <mpm/adaptive/particle_levels.h>
#include <mpm/adaptive/resampling.h>
#include <mpm/core/error.h>
#include <mpm/math/svd.h>

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>
#include <unordered_map>

namespace mpm::adaptive {

namespace {

//! splitmix64's finaliser: a well-mixed 64-bit hash of z.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

//! The next number of a counter-based stream, uniform in [0, 1).
double uniform(std::uint64_t& state) {
  state = mix(state);
  return static_cast<double>(state >> 11) * 0x1.0p-53;
}

//! The band width factor s_t = 2^t - 1 of transition t (resampling.h).
double band(int t) { return static_cast<double>((1 << t) - 1); }

template <int dim>
IVec<dim> cell_of(const Vec<dim>& x, const Vec<dim>& origin, double h) {
  IVec<dim> c;
  for (int a = 0; a < dim; ++a) c[a] = static_cast<int>(std::floor((x[a] - origin[a]) / h));
  return c;
}

//! A particle's place in a count or a merge group: level, material, cell; then its index, so
//! that sorting gives one deterministic order.
template <int dim>
struct Slot {
  int level;
  int material;
  IVec<dim> cell;
  std::size_t p;
  auto rank() const {
    std::array<int, dim + 2> r;
    r[0] = level;
    r[1] = material;
    for (int a = 0; a < dim; ++a) r[2 + a] = cell[a];
    return r;
  }
};

//! The slots sorted, and the start of each run of equal (level, material, cell).
template <int dim>
std::vector<std::size_t> sort_into_runs(std::vector<Slot<dim>>& slots) {
  std::sort(slots.begin(), slots.end(), [](const Slot<dim>& a, const Slot<dim>& b) {
    const auto ra = a.rank(), rb = b.rank();
    return ra != rb ? ra < rb : a.p < b.p;
  });
  std::vector<std::size_t> starts;
  for (std::size_t i = 0; i < slots.size(); ++i)
    if (i == 0 || slots[i].rank() != slots[i - 1].rank()) starts.push_back(i);
  starts.push_back(slots.size());
  return starts;
}

}  // namespace

template <int dim>
Mat<dim> random_rotation(std::uint64_t key) {
  std::uint64_t state = mix(key);
  constexpr double two_pi = 2.0 * std::numbers::pi;
  if constexpr (dim == 2) {
    const double theta = two_pi * uniform(state);
    Mat<2> R;
    R << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta);
    return R;
  } else {
    // Shoemake (1992): a uniform unit quaternion from three uniform numbers.
    const double u = uniform(state), a = two_pi * uniform(state), b = two_pi * uniform(state);
    const double s = std::sqrt(1.0 - u), t = std::sqrt(u);
    return Eigen::Quaterniond(t * std::cos(b), s * std::sin(a), s * std::cos(a), t * std::sin(b))
        .normalized()
        .toRotationMatrix();
  }
}

template <int dim>
Mat<dim> average_deformation(const std::vector<Mat<dim>>& F, const std::vector<double>& w) {
  MPM_VERIFY(F.size() == w.size() && !F.empty(), Error, "average_deformation: one weight per matrix");
  Eigen::Matrix4d quaternions = Eigen::Matrix4d::Zero();
  Mat<dim> stretch = Mat<dim>::Zero();
  double total = 0.0;
  for (std::size_t i = 0; i < F.size(); ++i) {
    const math::Svd<dim> f = math::svd<dim>(F[i]);
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    R.topLeftCorner<dim, dim>() = f.U * f.V.transpose();
    const Eigen::Quaterniond q(R);
    const Eigen::Vector4d v(q.w(), q.x(), q.y(), q.z());
    quaternions += w[i] * v * v.transpose();  // q and -q are the same rotation: v v^T is sign-free
    stretch += w[i] * f.V * f.sigma.asDiagonal() * f.V.transpose();
    total += w[i];
  }
  MPM_VERIFY(total > 0.0, Error, "average_deformation: the weights sum to zero");
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eigen(quaternions);
  const Eigen::Vector4d v = eigen.eigenvectors().col(3);  // eigenvalues ascend
  const Eigen::Matrix3d R = Eigen::Quaterniond(v[0], v[1], v[2], v[3]).normalized().toRotationMatrix();
  return R.topLeftCorner<dim, dim>() * (stretch / total);
}

namespace {

// Particle p (type q) and its 2^dim - 1 copies at first_new.. become p's children: the
// corners of the rotated cube of half-diagonal b/4 around it (b its box), each with the
// parent's APIC velocity there, a 2^-dim share of its mass and volume, and type q + 1.
template <int dim>
void place_children(Particles<dim>& P, std::size_t p, std::size_t first_new, const CellTree<dim>& tree,
                    int points_per_axis, const Mat<dim>& rotation) {
  std::vector<std::uint16_t>& level = P.template channel<std::uint16_t>(kParticleLevel);
  const int q = level[p];
  constexpr int children = 1 << dim;
  const Vec<dim> x = P.x[p], v = P.v[p];
  const Mat<dim> C = P.C[p];
  const double m = P.mass[p] / children, V = P.volume0[p] / children;
  const double offset = 0.25 * tree.dx(q) / points_per_axis;  // the sub-box centres: +-b/4
  for (int c = 0; c < children; ++c) {
    const std::size_t child = c == 0 ? p : first_new + c - 1;
    Vec<dim> o;
    for (int a = 0; a < dim; ++a) o[a] = (c >> a) & 1 ? offset : -offset;
    const Vec<dim> r = rotation * o;
    P.x[child] = x + r;
    P.v[child] = v + C * r;  // the parent's APIC velocity field at the child
    P.mass[child] = m;
    P.volume0[child] = V;
    level[child] = static_cast<std::uint16_t>(q + 1);
  }
}

}  // namespace

template <int dim>
void split_particle(Particles<dim>& P, std::size_t p, const CellTree<dim>& tree, int points_per_axis,
                    const Mat<dim>& rotation) {
  std::vector<std::uint16_t>& level = P.template channel<std::uint16_t>(kParticleLevel);
  const int q = level[p];
  MPM_VERIFY(q < tree.finest(), Error, "split_particle: particle " + std::to_string(p) + " is of the finest type");
  const std::size_t first_new = P.size();
  P.resize(first_new + (1 << dim) - 1);
  P.for_each_channel([&](const ChannelInfo&, auto& values) {
    for (std::size_t c = first_new; c < P.size(); ++c) values[c] = values[p];
  });
  place_children(P, p, first_new, tree, points_per_axis, rotation);
}

template <int dim>
void merge_particles(Particles<dim>& P, const std::vector<std::size_t>& group,
                     const std::vector<std::string>& deformation, std::vector<std::uint8_t>& erase) {
  MPM_VERIFY(group.size() >= 2, Error, "merge_particles: a group has two particles or more");
  std::vector<std::uint16_t>& level = P.template channel<std::uint16_t>(kParticleLevel);
  const std::size_t into = group[0];
  MPM_VERIFY(level[into] > 0, Error, "merge_particles: the particles are of the coarsest type");
  double mass = 0.0;
  for (std::size_t p : group) mass += P.mass[p];
  std::vector<double> w;
  for (std::size_t p : group) w.push_back(P.mass[p] / mass);
  P.for_each_channel([&](const ChannelInfo& info, auto& values) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    if constexpr (std::is_same_v<T, std::uint16_t>) {
      return;  // material and level: equal within a group (the level is lowered below)
    } else {
      if (info.use.derived) {
        constexpr double unknown = std::numeric_limits<double>::quiet_NaN();  // its owner recomputes it
        if constexpr (std::is_same_v<T, double>)
          values[into] = unknown;
        else
          values[into].setConstant(unknown);
        return;
      }
      if constexpr (std::is_same_v<T, double>) {
        if (info.name == "mass" || info.name == "volume0") {  // extensive
          double sum = 0.0;
          for (std::size_t p : group) sum += values[p];
          values[into] = sum;
          return;
        }
      }
      if constexpr (std::is_same_v<T, Mat<dim>>) {
        if (std::find(deformation.begin(), deformation.end(), info.name) != deformation.end()) {
          std::vector<Mat<dim>> F;
          for (std::size_t p : group) F.push_back(values[p]);
          values[into] = average_deformation<dim>(F, w);
          return;
        }
      }
      T mean = w[0] * values[group[0]];
      for (std::size_t i = 1; i < group.size(); ++i) mean += w[i] * values[group[i]];
      values[into] = mean;
    }
  });
  level[into] = static_cast<std::uint16_t>(level[into] - 1);
  for (std::size_t i = 1; i < group.size(); ++i) erase[group[i]] = 1;
}

template <int dim>
std::vector<double> surface_distance(const CellTree<dim>& tree, const std::vector<Vec<dim>>& x,
                                     const std::vector<std::uint16_t>& level, int points_per_axis, double max_distance,
                                     const LatticeWalls<dim>& walls) {
  const double h = tree.dx(tree.finest());
  const Vec<dim>& origin = tree.origin();
  const int max_depth = static_cast<int>(std::min(1e6, std::ceil(max_distance / h))) + 1;
  std::vector<double> d(x.size());
  if (x.empty()) return d;
  // Each particle covers its own finest cell and the cells its box overlaps. (Covering only the
  // cells whose centres lie in a box leaves holes inside a deformed body of coarse particles,
  // and a hole is a free surface to the distance.)
  auto box_of = [&](std::size_t p, IVec<dim>& lo, IVec<dim>& hi) {
    const double half = 0.5 * tree.dx(level[p]) / points_per_axis;
    for (int a = 0; a < dim; ++a) {
      lo[a] = static_cast<int>(std::floor((x[p][a] - half - origin[a]) / h));
      hi[a] = static_cast<int>(std::ceil((x[p][a] + half - origin[a]) / h)) - 1;
    }
  };
  // The box: the particles' extent widened by the largest particle's half-size; the cells the
  // particles mark, at most (2 half / h + 2)^dim each.
  Vec<dim> x_lo = x[0], x_hi = x[0];
  std::vector<std::size_t> per_level(static_cast<std::size_t>(tree.levels()), 0);
  for (std::size_t p = 0; p < x.size(); ++p) {
    MPM_VERIFY(level[p] < per_level.size(), InputError,
               "resampling: particle " + std::to_string(p) + " has type " + std::to_string(level[p]) +
                   ", outside the grid's levels [0, " + std::to_string(per_level.size() - 1) + "]");
    x_lo = x_lo.cwiseMin(x[p]);
    x_hi = x_hi.cwiseMax(x[p]);
    ++per_level[level[p]];
  }
  int coarsest = tree.finest();
  std::size_t marks = 0;
  for (int q = 0; q < tree.levels(); ++q)
    if (per_level[q] > 0) {
      coarsest = std::min(coarsest, q);
      marks += per_level[q] * static_cast<std::size_t>(std::pow(std::floor(tree.dx(q) / points_per_axis / h) + 2.0,
                                                                static_cast<double>(dim)));
    }
  const double widest = 0.5 * tree.dx(coarsest) / points_per_axis + h;
  const LatticeBox<dim> box(cell_of(Vec<dim>(x_lo.array() - widest), origin, h),
                            cell_of(Vec<dim>(x_hi.array() + widest), origin, h));
  if (box.dense_for(marks)) {
    // A compact body (the usual case): the cells marked in parallel on a dense box, then the
    // transform; no list of sites.
    const int cap = box.cap(max_depth);
    std::vector<int> cells(static_cast<std::size_t>(box.cells()), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
      for (std::size_t p = r.begin(); p != r.end(); ++p) {
        IVec<dim> first, last;
        box_of(p, first, last);
        auto mark = [&](const IVec<dim>& c) {
          std::atomic_ref<int>(cells[box.flat(c)]).store(cap, std::memory_order_relaxed);
        };
        mark(cell_of(x[p], origin, h));
        for_each_in_box<dim>(first, last, mark);
      }
    });
    manhattan_transform(box, cells, cap, walls);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 4096), [&](const auto& r) {
      for (std::size_t p = r.begin(); p != r.end(); ++p)
        d[p] = (cells[box.flat(cell_of(x[p], origin, h))] - 0.5) * h;  // <= cap <= max_depth + 1
    });
    return d;
  }
  // A scattered set: the first x.size() sites are the particles' own cells, then the other
  // cells their boxes overlap, for manhattan_depth.
  std::vector<IVec<dim>> sites;
  sites.reserve(2 * x.size());
  for (const Vec<dim>& xp : x) sites.push_back(cell_of(xp, origin, h));
  for (std::size_t p = 0; p < x.size(); ++p) {
    IVec<dim> first, last;
    box_of(p, first, last);
    for_each_in_box<dim>(first, last, [&](const IVec<dim>& c) {
      if (c != sites[p]) sites.push_back(c);
    });
  }
  const std::vector<int> depth = manhattan_depth(sites, max_depth, walls);
  for (std::size_t p = 0; p < x.size(); ++p) d[p] = (depth[p] - 0.5) * h;
  return d;
}

template <int dim>
LatticeWalls<dim> lattice_walls(const geometry::DomainWalls<dim>& walls, SurfaceWalls surface, const Vec<dim>& origin,
                                double h) {
  const auto bounds = [&](int axis, geometry::Side side) {  // a closed wall that is no surface
    const std::optional<geometry::Contact>& c = walls.wall(axis, side);
    const bool rough = c && (c->type == geometry::ContactType::sticky ||
                             (c->type == geometry::ContactType::separate && c->friction > 0));
    return c && surface != SurfaceWalls::all && !(surface == SurfaceWalls::rough && rough);
  };
  // The material meets a wall `thickness` inside the domain's face (the nodes' boundary layer).
  // A cell that straddles the face is inside (it may be empty: a surface).
  constexpr double slack = 1e-6;  // a face on the lattice, up to round-off
  LatticeWalls<dim> lattice;
  for (int a = 0; a < dim; ++a) {
    if (bounds(a, geometry::Side::lower))
      lattice.lo[a] = static_cast<int>(std::floor((walls.lo()[a] + walls.thickness() - origin[a]) / h + slack));
    if (bounds(a, geometry::Side::upper))
      lattice.hi[a] = static_cast<int>(std::ceil((walls.hi()[a] - walls.thickness() - origin[a]) / h - slack)) - 1;
  }
  return lattice;
}

template <int dim>
ResampleCounts resample_particles(Particles<dim>& P, const CellTree<dim>& tree, int points_per_axis,
                                  const ResampleSettings& settings, const std::vector<std::string>& deformation,
                                  std::uint64_t step, const LatticeWalls<dim>& walls) {
  ResampleCounts counts;
  const std::size_t n = P.size();
  const int finest = tree.finest();
  if (n == 0 || finest == 0) return counts;
  std::vector<std::uint16_t>& level = P.template channel<std::uint16_t>(kParticleLevel);
  const std::vector<double> d =
      surface_distance(tree, P.x, level, points_per_axis, band(finest) * settings.d_large, walls);

  // Candidates by the distance bands.
  std::vector<Slot<dim>> splits, merges;
  for (std::size_t p = 0; p < n; ++p) {
    const int q = level[p];
    if (d[p] <= settings.d_small) continue;
    if (q < finest && d[p] < band(finest - q) * settings.d_medium)
      splits.push_back({q, P.material[p], cell_of(P.x[p], tree.origin(), tree.dx(q)), p});
    else if (q > 0 && d[p] > band(finest - q + 1) * settings.d_large)
      merges.push_back({q, P.material[p], cell_of(P.x[p], tree.origin(), tree.dx(q - 1) / points_per_axis), p});
  }

  // Split guard: the particles of each level in each cell of that level, counted in the split
  // candidates' cells only (a few hundred; most particles are of a level with none).
  const int nominal = ipow(points_per_axis, dim);
  std::vector<std::size_t> allowed_splits;
  if (!splits.empty()) {
    std::vector<std::unordered_map<std::uint64_t, int>> per_cell(tree.levels());
    auto key = [](const IVec<dim>& c) {
      std::uint64_t k = 0;
      for (int a = dim - 1; a >= 0; --a) k = (k << 21) | static_cast<std::uint64_t>(c[a] + 1);
      return k;
    };
    for (const Slot<dim>& s : splits) per_cell[s.level].emplace(key(s.cell), 0);
    for (std::size_t p = 0; p < n; ++p) {
      auto& cells = per_cell[level[p]];
      if (cells.empty()) continue;
      if (const auto it = cells.find(key(cell_of(P.x[p], tree.origin(), tree.dx(level[p])))); it != cells.end())
        ++it->second;
    }
    for (const Slot<dim>& s : splits) {
      const int count = per_cell[s.level][key(s.cell)];
      if (2 * count >= nominal && count <= 2 * nominal) allowed_splits.push_back(s.p);
    }
  }

  // Merge groups: same level, material and coarse sub-cell, holding between 3/4 and 3/2 of a
  // coarse particle's nominal volume. (A guard on the count alone let 2 particles merge into a
  // light coarse one that split into 4 lighter fine ones: the count grew without bound.)
  std::vector<std::uint8_t> erase(n, 0);
  if (!merges.empty()) {
    const std::vector<std::size_t> runs = sort_into_runs(merges);
    std::vector<std::size_t> group;
    for (std::size_t r = 0; r + 1 < runs.size(); ++r) {
      const std::size_t size = runs[r + 1] - runs[r];
      const double nominal_volume = std::pow(tree.dx(merges[runs[r]].level - 1) / points_per_axis, dim);
      double volume = 0.0;
      for (std::size_t i = runs[r]; i < runs[r + 1]; ++i) volume += P.volume0[merges[i].p];
      if (size < 2 || volume < 0.75 * nominal_volume || volume > 1.5 * nominal_volume) continue;
      group.clear();
      for (std::size_t i = runs[r]; i < runs[r + 1]; ++i) group.push_back(merges[i].p);
      merge_particles(P, group, deformation, erase);
      counts.merged += size;
      ++counts.groups;
    }
  }

  // The merged-away particles dropped and the split ones' children appended in one gather: the
  // particles kept, in order, then per split its 2^dim - 1 copies (the order of splitting
  // each in turn and then erasing, without growing every channel and compacting it again).
  if (allowed_splits.empty() && counts.merged == 0) return counts;
  constexpr std::size_t copies = (1 << dim) - 1;
  std::vector<std::uint32_t> order;
  order.reserve(n + copies * allowed_splits.size());
  std::vector<std::size_t> split_at;  // the split particles' indices after the gather
  split_at.reserve(allowed_splits.size());
  for (std::size_t p = 0, next = 0; p < n; ++p) {
    if (erase[p]) continue;
    if (next < allowed_splits.size() && allowed_splits[next] == p) {
      split_at.push_back(order.size());
      ++next;
    }
    order.push_back(static_cast<std::uint32_t>(p));
  }
  MPM_ASSERT(split_at.size() == allowed_splits.size());  // ascending, none merged
  for (std::size_t p : allowed_splits) order.insert(order.end(), copies, static_cast<std::uint32_t>(p));
  const std::size_t first_copy = order.size() - copies * allowed_splits.size();
  P.permute(order);
  for (std::size_t i = 0; i < allowed_splits.size(); ++i) {
    const std::size_t p = allowed_splits[i];
    place_children(P, split_at[i], first_copy + copies * i, tree, points_per_axis, random_rotation<dim>(mix(step) ^ p));
    ++counts.split;
  }
  return counts;
}

#define MPM_INSTANTIATE(dim)                                                                                       \
  template Mat<dim> random_rotation<dim>(std::uint64_t);                                                           \
  template Mat<dim> average_deformation<dim>(const std::vector<Mat<dim>>&, const std::vector<double>&);            \
  template void split_particle(Particles<dim>&, std::size_t, const CellTree<dim>&, int, const Mat<dim>&);          \
  template void merge_particles(Particles<dim>&, const std::vector<std::size_t>&, const std::vector<std::string>&, \
                                std::vector<std::uint8_t>&);                                                       \
  template std::vector<double> surface_distance(const CellTree<dim>&, const std::vector<Vec<dim>>&,                \
                                                const std::vector<std::uint16_t>&, int, double,                    \
                                                const LatticeWalls<dim>&);                                         \
  template ResampleCounts resample_particles(Particles<dim>&, const CellTree<dim>&, int, const ResampleSettings&,  \
                                             const std::vector<std::string>&, std::uint64_t,                       \
                                             const LatticeWalls<dim>&);                                            \
  template LatticeWalls<dim> lattice_walls(const geometry::DomainWalls<dim>&, SurfaceWalls, const Vec<dim>&, double);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm::adaptive
