#pragma once
//! The interface between the host code of the CUDA back-end (device_step.cpp, compiled by the
//! C++ compiler with Eigen) and its kernels (device_solid.cu, compiled by nvcc): plain arrays
//! and structs, no Eigen and no CUDA types. Internal.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mpm::cuda::detail {

enum class Elasticity : int { fixed_corotated = 0, neo_hookean = 1, hencky_stvk = 2 };
enum class Plasticity : int { none = 0, drucker_prager = 1, von_mises = 2 };

//! One material as the device sees it (filled on the host from solid::Material).
struct DeviceMaterial {
  Elasticity elasticity;
  Plasticity plasticity;
  double mu, lambda;
  double alpha, k;      //!< Drucker-Prager cone (drucker_prager.h)
  double yield_stress;  //!< von Mises [Pa]
};

//! An analytic obstacle (geometry/collider.h) as the device applies it.
struct DeviceCollider {
  enum Shape : int { half_space = 0, box = 1, sphere = 2 } shape = half_space;
  double a[3] = {0, 0, 0};  //!< half space: point; box: centre; sphere: centre [m]
  double b[3] = {0, 0, 0};  //!< half space: unit normal; box: half sizes; sphere: radius in b[0]
  double velocity[3] = {0, 0, 0};
  bool translating = true;  //!< Motion::translating: the shape moves with `velocity`
  bool hollow = false;
  double until = 1e300;  //!< [s]
  int contact = 2;       //!< geometry::ContactType: 0 sticky, 1 slip, 2 separate
  double friction = 0.0;
};

//! The closed faces of the domain box (geometry::DomainWalls).
struct DeviceWalls {
  bool present = false;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  double layer = 0.0;                         //!< thickness (1 + 1e-9) [m]
  int contact[6] = {-1, -1, -1, -1, -1, -1};  //!< per face (axis, lower/upper): -1 open, else ContactType
  double friction[6] = {0, 0, 0, 0, 0, 0};
};

//! Everything the device step needs besides the particles.
struct DeviceScene {
  double origin[3];                          //!< grid node 0 [m]
  double dx;                                 //!< [m]
  int node_counts[3];                        //!< nodes per axis
  double gravity[3];                         //!< [m/s^2]
  double cfl, wave_cfl, wave_speed, max_dt;  //!< the time step (stages::TimeStepControl)
  std::vector<DeviceMaterial> materials;
  std::vector<DeviceCollider> colliders;
  DeviceWalls walls;
  //! The transfer benchmark (Gao et al. 2017, Table 1; bench/bench_cuda.cpp): P2G of mass and
  //! APIC momentum without the stress, G2P of v, C and x without F, return map or stress.
  bool transfers_only = false;
  //! The P2G scatter into a particle block's shared tile. `automatic` takes the one measured
  //! faster (docs/performance.md, "The CUDA step"): in single precision the warp-level reduction
  //! of peers (P2G 0.65x on the transfer benchmark, 0.67x in the 3D column collapse with the
  //! stress), in double precision one shared atomic per particle and node (shuffles of doubles
  //! cost more than the atomics they save: 1.6x). The two others force one (bench_cuda --p2g,
  //! the scatter test).
  enum class Scatter { automatic, warp_reduced, one_atomic };
  Scatter p2g_scatter = Scatter::automatic;
};

//! The particle channels the device holds, component-major (channel[c * n + p]) in double on the
//! host side: positions x (3), velocities v (3), APIC C (9, row-major), elastic F (9,
//! row-major), plastic state (1), mass, volume0, material.
struct HostParticles {
  std::size_t n = 0;
  std::vector<double> x, v, C, F, plastic, mass, volume0;
  std::vector<std::uint16_t> material;
};

//! Seconds of the last step's phases (events on the device's stream).
struct StepTimes {
  double sort = 0, p2g = 0, grid = 0, g2p = 0;
  bool reordered = false;  //!< the step moved the particle data into block order (in `sort`)
};

class DeviceSolid {
public:
  virtual ~DeviceSolid() = default;
  //! Copies the particles to the device (replacing any held) and computes their stress.
  virtual void upload(const HostParticles& particles) = 0;
  //! The particles' current state; their order is the order of upload(). Not const: the
  //! device's spare particle buffer serves as scratch.
  virtual void download(HostParticles& particles) = 0;
  //! The step the CFL and wave conditions allow for the current velocities [s] (> dt_limit
  //! possible: the caller clips it).
  virtual double stable_dt() = 0;
  //! One explicit step of length dt ending at time t_end [s]. Throws mpm::NumericalError on a
  //! non-finite grid velocity or F, or a particle outside the grid.
  virtual void step(double dt, double t_end) = 0;
  virtual StepTimes last_times() const = 0;
  //! Device bytes held now.
  virtual std::size_t memory_bytes() const = 0;
};

//! A device solid in float or double. Throws mpm::Error when no device is usable.
std::unique_ptr<DeviceSolid> make_device_solid(const DeviceScene& scene, bool single_precision);

//! "" when a CUDA device is usable, else why not.
std::string device_unavailable_reason();
//! The device's name and memory, e.g. "NVIDIA H100 80GB HBM3 (79.1 GiB free of 79.6 GiB)".
std::string device_description();
//! Free device memory [B] (0 without a device).
std::size_t device_free_bytes();
//! Bytes the device step holds per particle, per active grid block and per block of the
//! domain's block table, for the memory check.
std::size_t bytes_per_particle(bool single_precision);
std::size_t bytes_per_block(bool single_precision);
std::size_t bytes_per_table_entry();

}  // namespace mpm::cuda::detail
