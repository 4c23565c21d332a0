#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace mpm::stages {

//! An emitter: a stream of particles entering the box [lo, hi] through its upstream face (the
//! face normal to the flow axis a = argmax |v_a| that the velocity v points away from), at the
//! volume flux |v_a| A (A: the area of that face). The particles lie on the seeding lattice
//! of geometry::seed_box (spacing h = dx / k, k^dim = particles_per_cell) carried along axis a
//! at |v_a|: a new layer enters each time the lattice has moved on by h, so the number of
//! layers emitted by time t is a function of t alone, N(t) = floor((|v_a| (t - start) + delta) / h),
//! delta in [0, h] the distance of the first inner lattice plane from the face. The emitted
//! mass is N(t) n_A m_p (n_A lattice points per layer), within one layer of rho |v_a| A (t - start)
//! (exactly so when the face's edges lie on lattice planes), whatever the material does after it
//! enters. The step [t, t + dt] emits the layers that cross by t + dt, each placed where the
//! lattice is at t (up to |v_a| dt short of the face) with velocity v and C = 0, so that the
//! step's advection carries it in and the state at the end of the step holds exactly N(t + dt)
//! layers. Transverse positions are the lattice's (the tangential part of v does not shift them).
//!
//! Preconditions: dt is set (a time-step stage runs before), and a sort stage follows (the
//! buckets are cleared when particles are added). On its first run at time t the source takes
//! the N(t) layers as emitted (none at the start): a run restarted from a checkpoint at t, whose
//! particles hold them, continues the same stream.
template <int dim>
class ParticleSource final : public Stage<MpmState<dim>> {
public:
  struct Settings {
    Vec<dim> lo, hi;                                        //!< the box [m]
    Vec<dim> velocity;                                      //!< v of the stream [m/s], not zero
    double dx = 0.0;                                        //!< grid spacing of the seeding lattice [m]
    int particles_per_cell = 1;                             //!< k^dim
    double particle_mass = 0.0;                             //!< m_p [kg] (fluid: n_w rho_w V_p; grains: rho_s V_p)
    double particle_volume = 0.0;                           //!< V_p [m^dim] (usually dx^dim / particles_per_cell)
    std::uint16_t material = 0;                             //!< material index of the emitted particles
    double start = 0.0;                                     //!< [s]
    double stop = std::numeric_limits<double>::infinity();  //!< [s], >= start
  };

  //! Throws InputError for a zero velocity, an empty box, a face without lattice points,
  //! m_p or V_p <= 0, or stop < start.
  explicit ParticleSource(const Settings& settings);

  std::string name() const override { return "source"; }
  std::vector<std::string> reads() const override { return {}; }
  std::vector<std::string> writes() const override {
    return {"particle.x", "particle.v", "particle.C", "particle.mass", "particle.volume0", "particle.material"};
  }
  void run(MpmState<dim>& s) override;

  //! N(t): layers emitted from start to t [s] (0 before start; counted up to stop).
  std::int64_t layers_by(double t) const;
  //! Mass emitted from start to the end of the last run's step [kg] (N(t + dt) n_A m_p).
  double emitted_mass() const { return double(emitted_) * double(face_points_.size()) * settings_.particle_mass; }
  //! inflow_mass: the mass emitted since the start [kg].
  std::vector<Diagnostic> diagnostics() const override { return {{"inflow_mass", emitted_mass(), true}}; }
  //! Particles per layer n_A.
  std::size_t layer_size() const { return face_points_.size(); }
  const Settings& settings() const { return settings_; }

private:
  Settings settings_;
  int axis_ = 0;
  double sign_ = 1.0;                  // +1: flow towards +axis
  double h_ = 0.0;                     // lattice spacing [m]
  double first_plane_ = 0.0;           // along-axis position of the first inner lattice plane at start [m]
  double delta_ = 0.0;                 // its distance from the upstream face [m]
  std::vector<Vec<dim>> face_points_;  // transverse lattice of a layer (axis coordinate 0)
  std::int64_t emitted_ = 0;
  bool started_ = false;
};

}  // namespace mpm::stages
