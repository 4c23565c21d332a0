// Emitter (particle_source.h). With a = argmax |v_a|, s = sign(v_a), h = dx / k, the upstream
// face x_a = f (f = lo_a for s > 0, hi_a for s < 0) and the innermost lattice plane at or
// inside it, x_a = c0 (|c0 - f| = delta in [0, h)):
//   d(t)   = |v_a| (min(t, stop) - start)                     distance the stream has moved on
//   N(t)   = floor((d(t) + delta) / h)                        layers that crossed the face
//   the step [t, t + dt] emits the layers n = N(t) + 1 .. N(t + dt), each at the position of
//   the moving lattice at t:  x_a = c0 - s n h + s |v_a| (t - start)  (the step's advection
//   carries it in), so after the step the particles hold exactly N(t + dt) layers;
//   emitted mass = N(t) n_A m_p,  |N(t) n_A h^dim - |v_a| A (t - start)| <= n_A h^dim.
#include <mpm/core/stages/particle_source.h>

#include <mpm/core/error.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace mpm::stages {

template <int dim>
ParticleSource<dim>::ParticleSource(const Settings& settings) : settings_(settings) {
  const Settings& c = settings_;
  verify<InputError>(c.velocity.allFinite() && c.velocity.norm() > 0.0, "source: the velocity must not be zero");
  verify<InputError>((c.hi.array() > c.lo.array()).all(), "source: the box hi must exceed lo on every axis");
  verify<InputError>(c.particle_mass > 0.0 && c.particle_volume > 0.0,
                     "source: the particle mass and volume must be > 0");
  verify<InputError>(c.stop >= c.start, "source: stop must not precede start");
  c.velocity.cwiseAbs().maxCoeff(&axis_);
  sign_ = c.velocity[axis_] > 0.0 ? 1.0 : -1.0;
  h_ = c.dx / geometry::lattice_points_per_axis<dim>(c.particles_per_cell);

  // The transverse lattice: seed_box over a slab holding the single lattice plane x_a = h / 2.
  Vec<dim> slab_lo = c.lo, slab_hi = c.hi;
  slab_lo[axis_] = 0.0;
  slab_hi[axis_] = h_;
  face_points_ = geometry::seed_box<dim>(slab_lo, slab_hi, c.dx, c.particles_per_cell, 0.0, 0);
  verify<InputError>(!face_points_.empty(),
                     "source: the upstream face of the box holds no point of the "
                     "seeding lattice (spacing " +
                         std::to_string(h_) + " m)");
  for (Vec<dim>& q : face_points_) q[axis_] = 0.0;

  // Planes of the lattice lie at (i + 1/2) h (seeding.h).
  const double face = sign_ > 0.0 ? c.lo[axis_] : c.hi[axis_];
  const double i0 = sign_ > 0.0 ? std::ceil(face / h_ - 0.5) : std::floor(face / h_ - 0.5);
  first_plane_ = (i0 + 0.5) * h_;
  delta_ = std::clamp(sign_ * (first_plane_ - face), 0.0, h_);
}

template <int dim>
std::int64_t ParticleSource<dim>::layers_by(double t) const {
  if (t < settings_.start) return 0;
  const double d = std::abs(settings_.velocity[axis_]) * (std::min(t, settings_.stop) - settings_.start);
  return static_cast<std::int64_t>(std::floor((d + delta_) / h_));
}

template <int dim>
void ParticleSource<dim>::run(MpmState<dim>& s) {
  const std::int64_t target = layers_by(s.time + s.dt);
  if (!started_) {
    started_ = true;
    emitted_ = layers_by(s.time);  // 0 at the start; after a restart, the layers in the particles
  }
  if (target == emitted_) return;
  // Room grows by a quarter, not by std::vector's doubling: against an outflow the count
  // levels off, and doubling would hold up to twice the particles for the rest of the run.
  const std::size_t needed = s.particles.size() + static_cast<std::size_t>(target - emitted_) * face_points_.size();
  if (needed > s.particles.capacity())
    s.particles.reserve(std::max(needed, s.particles.size() + s.particles.size() / 4));
  const double moved = std::abs(settings_.velocity[axis_]) * (s.time - settings_.start);
  for (std::int64_t n = emitted_ + 1; n <= target; ++n) {
    const double along = first_plane_ - sign_ * double(n) * h_ + sign_ * moved;
    for (Vec<dim> x : face_points_) {
      x[axis_] = along;
      s.particles.push_back(x, settings_.velocity, settings_.particle_mass, settings_.particle_volume,
                            settings_.material);
    }
  }
  emitted_ = target;
  s.buckets = ParticleBuckets<dim>{};  // stale: the sort that follows rebuilds them
}

template class ParticleSource<2>;
template class ParticleSource<3>;

}  // namespace mpm::stages
