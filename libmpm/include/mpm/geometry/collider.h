#pragma once
//! Collision objects of the grid velocity update (Gao et al. 2017, sec. 3.2 step 4): after the
//! grid velocity update, every node inside an obstacle gets the obstacle's contact condition on
//! its velocity relative to the obstacle.
//!
//!   Collider     one obstacle: a shape moving at a constant velocity, phi(x, t) = phi0(x - v t),
//!                or hollow (material inside it), or with a turning surface (a drum)
//!   DomainWalls  the faces of the simulation box, each with a boundary layer of nodes
//!   ColliderSet  all obstacles of a scene, applied in order, the walls last
#include <mpm/core/types.h>
#include <mpm/geometry/contact.h>
#include <mpm/geometry/level_set.h>
#include <mpm/geometry/signed_distance.h>

#include <array>
#include <limits>
#include <optional>
#include <utility>
#include <variant>
#include <vector>

namespace mpm::geometry {

template <int dim>
using Shape = std::variant<HalfSpace<dim>, Box<dim>, Sphere<dim>, Cylinder<dim>, LevelSetShape<dim>>;

//! How a collider's velocity acts: it moves the shape, or the shape stays and only the material
//! on it moves (an inlet that prescribes the inflow velocity, a conveyor belt).
enum class Motion { translating, fixed };

template <int dim>
class Collider {
public:
  //! `velocity` [m/s] is the obstacle's velocity: with Motion::translating the shape is at
  //! x + velocity * t at time t [s]; with Motion::fixed it stays at x and nodes inside still
  //! get the contact condition relative to `velocity`.
  //! Throws InputError when the friction coefficient is negative or not finite.
  Collider(Shape<dim> shape, const Contact& contact, const Vec<dim>& velocity = Vec<dim>::Zero(),
           Motion motion = Motion::translating);

  //! A hollow obstacle is the outside of its shape: material sits inside (a drum, a tank).
  void set_hollow(bool hollow) { hollow_ = hollow; }
  //! Another contact condition for the same obstacle (a second phase meeting it differently).
  //! Throws InputError as the constructor.
  void set_contact(const Contact& contact);
  //! The obstacle exists until time `t` [s] and is gone after it (a grip that releases a body).
  void set_until(double t) { until_ = t; }
  double until() const { return until_; }
  //! The obstacle's surface turns at `omega` [rad/s] (2D: omega.z) about `center` [m]: its
  //! velocity at x is velocity + omega x (x - center). The shape itself does not turn, so this
  //! is for shapes symmetric about that axis (a sphere, a cylinder about its axis: a drum).
  void set_rotation(const Eigen::Vector3d& omega, const Vec<dim>& center) {
    omega_ = omega;
    center_ = center;
  }

  double phi(const Vec<dim>& x, double t) const;       //!< [m], negative inside; +inf after until()
  Vec<dim> normal(const Vec<dim>& x, double t) const;  //!< unit, out of the obstacle
  //! The obstacle's velocity at x [m/s].
  Vec<dim> velocity_at(const Vec<dim>& x) const;
  //! When phi(x, t) <= 0, replaces the node velocity v [m/s] by v_c + contact.apply(v - v_c, n)
  //! with v_c = velocity_at(x) (for a material point: contact.h, ContactPoint).
  void project(const Vec<dim>& x, double t, Vec<dim>& v, ContactPoint point = ContactPoint::node) const;
  //! The linear part of project for an implicit solve: appends to `fixed` the unit directions
  //! in which the obstacle prescribes the velocity v of a node at x (every axis for sticky
  //! contact, the normal for slip contact and for separating contact that v approaches; none
  //! outside the obstacle). Friction is left to project.
  void fixed_directions(const Vec<dim>& x, double t, const Vec<dim>& v, std::vector<Vec<dim>>& fixed,
                        ContactPoint point = ContactPoint::node) const;

  const Shape<dim>& shape() const { return shape_; }
  const Contact& contact() const { return contact_; }
  const Vec<dim>& velocity() const { return velocity_; }
  Motion motion() const { return motion_; }
  const Eigen::Vector3d& angular_velocity() const { return omega_; }
  bool hollow() const { return hollow_; }
  //! The largest obstacle speed at points within `reach` [m] of the rotation centre [m/s].
  double speed_within(double reach) const { return velocity_.norm() + omega_.norm() * reach; }
  bool is_level_set() const { return std::holds_alternative<LevelSetShape<dim>>(shape_); }

private:
  Shape<dim> shape_;
  Contact contact_;
  Vec<dim> velocity_;
  Motion motion_;
  bool hollow_ = false;
  double until_ = std::numeric_limits<double>::infinity();
  Eigen::Vector3d omega_ = Eigen::Vector3d::Zero();
  Vec<dim> center_ = Vec<dim>::Zero();
  Vec<dim> shape_position(const Vec<dim>& x, double t) const;  // x in the frame of the shape
};

enum class Side { lower, upper };

//! The 2 dim faces of the domain box [lo, hi] as fixed walls. A node whose distance to a closed
//! wall is <= thickness gets that wall's contact with the normal pointing into the domain;
//! an open wall (std::nullopt) lets material leave the domain.
template <int dim>
class DomainWalls {
public:
  //! Every wall closed with `contact`; `thickness` [m] > 0 is the depth of the boundary layer.
  DomainWalls(const Vec<dim>& lo, const Vec<dim>& hi, double thickness, const Contact& contact);

  void set_wall(int axis, Side side, const std::optional<Contact>& contact);
  const std::optional<Contact>& wall(int axis, Side side) const { return walls_[index(axis, side)]; }

  void project(const Vec<dim>& x, Vec<dim>& v, ContactPoint point = ContactPoint::node) const;
  //! Whether x lies in the boundary layer of a closed wall (the layer project() acts on).
  bool in_layer(const Vec<dim>& x) const;
  //! As Collider::fixed_directions, for the closed walls whose layer holds x.
  void fixed_directions(const Vec<dim>& x, const Vec<dim>& v, std::vector<Vec<dim>>& fixed,
                        ContactPoint point = ContactPoint::node) const;

  const Vec<dim>& lo() const { return lo_; }
  const Vec<dim>& hi() const { return hi_; }
  double thickness() const { return thickness_; }

private:
  static int index(int axis, Side side) { return 2 * axis + (side == Side::upper ? 1 : 0); }
  //! The layer's depth with room for round-off: a node on the inner face of the layer belongs
  //! to the wall, and its coordinate lo + i dx may round a few ulps beyond lo + thickness
  //! (dx = 1/24 is not exact in binary).
  double reach() const { return thickness_ * (1.0 + 1e-9); }
  Vec<dim> lo_;
  Vec<dim> hi_;
  double thickness_;
  std::array<std::optional<Contact>, 2 * dim> walls_;
};

template <int dim>
class ColliderSet {
public:
  void add(Collider<dim> collider) { colliders_.push_back(std::move(collider)); }
  void set_walls(const DomainWalls<dim>& walls) { walls_ = walls; }

  //! Applies every collider in the order added, then the walls, so that no node velocity
  //! leaves the domain through a closed wall.
  void project(const Vec<dim>& x, double t, Vec<dim>& v, ContactPoint point = ContactPoint::node) const;
  //! The orthogonal projector onto the velocity directions that no obstacle prescribes at x for
  //! a node moving at v (identity in free space, zero for a sticky node): the degrees of
  //! freedom an implicit solve leaves to the node (Collider::fixed_directions).
  Mat<dim> free_directions(const Vec<dim>& x, double t, const Vec<dim>& v,
                           ContactPoint point = ContactPoint::node) const;
  //! Whether an obstacle prescribes (part of) the velocity of a node at x at time t: x inside or
  //! on a collider (phi <= 0, where project() acts) or in the layer of a closed wall.
  bool prescribes(const Vec<dim>& x, double t) const;
  bool uses_level_sets() const;
  bool empty() const { return colliders_.empty() && !walls_; }

  const std::vector<Collider<dim>>& colliders() const { return colliders_; }
  const std::optional<DomainWalls<dim>>& walls() const { return walls_; }

private:
  std::vector<Collider<dim>> colliders_;
  std::optional<DomainWalls<dim>> walls_;
};

}  // namespace mpm::geometry
