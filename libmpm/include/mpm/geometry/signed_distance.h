#pragma once
//! Analytic collision obstacles given by their exact signed distance.
//!
//! Every shape offers phi(x): the Euclidean signed distance to its surface [m], NEGATIVE INSIDE
//! the solid, and normal(x) = grad phi / |grad phi|: the unit normal pointing out of the solid.
//! |grad phi| = 1 wherever phi is differentiable; on a kink (a box edge seen from inside, the
//! centre of a sphere, the axis of a cylinder) normal() returns one of the one-sided gradients.
#include <mpm/core/error.h>
#include <mpm/core/types.h>

#include <Eigen/Geometry>
#include <cmath>
#include <optional>

namespace mpm::geometry {

namespace detail {

//! Signed distance of a point y >= 0 to the box |y_i| <= half_i, written with q = y - half
//! (exact inside and outside), and its gradient with respect to q.
template <int n>
struct BoxDistance {
  double phi;
  Vec<n> gradient;
};

template <int n>
BoxDistance<n> box_distance(const Vec<n>& q) {
  const Vec<n> outside = q.cwiseMax(0.0);
  const double outside_distance = outside.norm();
  if (outside_distance > 0.0) return {outside_distance, outside / outside_distance};
  int nearest_face = 0;
  const double inside_distance = q.maxCoeff(&nearest_face);  // <= 0: the closest face
  return {inside_distance, Vec<n>::Unit(nearest_face)};
}

inline double sign_or_plus(double value) { return value < 0.0 ? -1.0 : 1.0; }

}  // namespace detail

//! The solid {(x - point) . normal < 0}: a floor, a wall or a ramp; it lies on the side
//! opposite to `normal`.
template <int dim>
class HalfSpace {
public:
  HalfSpace(const Vec<dim>& point, const Vec<dim>& normal) : point_(point) {
    verify<InputError>(normal.norm() > 0.0, "half space: the normal must be a nonzero vector");
    normal_ = normal.normalized();
  }
  double phi(const Vec<dim>& x) const { return (x - point_).dot(normal_); }
  Vec<dim> normal(const Vec<dim>&) const { return normal_; }
  const Vec<dim>& point() const { return point_; }

private:
  Vec<dim> point_;
  Vec<dim> normal_;
};

//! The axis-aligned solid box [lo, hi] [m].
template <int dim>
class Box {
public:
  Box(const Vec<dim>& lo, const Vec<dim>& hi) : center_(0.5 * (lo + hi)), half_(0.5 * (hi - lo)) {
    verify<InputError>((hi.array() > lo.array()).all(), "box: hi must exceed lo in every component");
  }
  double phi(const Vec<dim>& x) const { return distance(x).phi; }
  Vec<dim> normal(const Vec<dim>& x) const {
    // The box is symmetric about its centre: mirror x into the positive quadrant and back.
    const Vec<dim> gradient = distance(x).gradient;
    Vec<dim> n;
    for (int i = 0; i < dim; ++i) n[i] = detail::sign_or_plus(x[i] - center_[i]) * gradient[i];
    return n;
  }
  Vec<dim> lo() const { return center_ - half_; }
  Vec<dim> hi() const { return center_ + half_; }
  const Vec<dim>& center() const { return center_; }
  const Vec<dim>& half_size() const { return half_; }

private:
  detail::BoxDistance<dim> distance(const Vec<dim>& x) const {
    return detail::box_distance<dim>(Vec<dim>((x - center_).cwiseAbs() - half_));
  }
  Vec<dim> center_;
  Vec<dim> half_;
};

//! A solid ball (a disk in 2D).
template <int dim>
class Sphere {
public:
  Sphere(const Vec<dim>& center, double radius) : center_(center), radius_(radius) {
    verify<InputError>(radius > 0.0, "sphere: the radius must be > 0");
  }
  double phi(const Vec<dim>& x) const { return (x - center_).norm() - radius_; }
  Vec<dim> normal(const Vec<dim>& x) const {
    const Vec<dim> d = x - center_;
    const double r = d.norm();
    return r > 0.0 ? Vec<dim>(d / r) : Vec<dim>::Unit(0);
  }
  const Vec<dim>& center() const { return center_; }
  double radius() const { return radius_; }

private:
  Vec<dim> center_;
  double radius_;
};

//! A solid circular cylinder. In 3D: the points within `radius` of the axis through `point`
//! along `axis`, infinite or capped at |(x - point) . axis| <= half_length. In 2D the axis is
//! out of the plane, so the cylinder is the disk of `radius` around `point`.
template <int dim>
class Cylinder {
public:
  Cylinder(const Vec<dim>& point, double radius) requires(dim == 2)
      : point_(point), axis_(Vec<dim>::Zero()), radius_(radius) {
    verify<InputError>(radius > 0.0, "cylinder: the radius must be > 0");
  }
  Cylinder(const Vec<dim>& point, const Vec<dim>& axis, double radius,
           std::optional<double> half_length = std::nullopt) requires(dim == 3)
      : point_(point), radius_(radius), half_length_(half_length) {
    verify<InputError>(axis.norm() > 0.0, "cylinder: the axis must be a nonzero vector");
    verify<InputError>(radius > 0.0, "cylinder: the radius must be > 0");
    verify<InputError>(!half_length || *half_length > 0.0, "cylinder: the half length must be > 0");
    axis_ = axis.normalized();
  }

  double phi(const Vec<dim>& x) const {
    if constexpr (dim == 2) {
      return (x - point_).norm() - radius_;
    } else {
      const Split s = split(x);
      if (!half_length_) return s.radial_distance - radius_;
      return detail::box_distance<2>(q(s)).phi;
    }
  }

  Vec<dim> normal(const Vec<dim>& x) const {
    if constexpr (dim == 2) {
      const Vec<dim> d = x - point_;
      const double r = d.norm();
      return r > 0.0 ? Vec<dim>(d / r) : Vec<dim>::Unit(0);
    } else {
      const Split s = split(x);
      const Vec<dim> radial_unit =
          s.radial_distance > 0.0 ? Vec<dim>(s.radial / s.radial_distance) : Vec<dim>(axis_.unitOrthogonal());
      if (!half_length_) return radial_unit;
      // Chain rule through q = (|radial| - radius, |along| - half_length).
      const Vec<2> g = detail::box_distance<2>(q(s)).gradient;
      return g[0] * radial_unit + g[1] * detail::sign_or_plus(s.along) * axis_;
    }
  }

  const Vec<dim>& point() const { return point_; }
  const Vec<dim>& axis() const { return axis_; }  //!< unit (3D); zero in 2D
  double radius() const { return radius_; }

private:
  //! x - point split into its component along the axis and the rest.
  struct Split {
    double along;
    Vec<dim> radial;
    double radial_distance;
  };
  Split split(const Vec<dim>& x) const {
    const Vec<dim> d = x - point_;
    const double along = d.dot(axis_);
    const Vec<dim> radial = d - along * axis_;
    return {along, radial, radial.norm()};
  }
  Vec<2> q(const Split& s) const { return {s.radial_distance - radius_, std::abs(s.along) - *half_length_}; }

  Vec<dim> point_;
  Vec<dim> axis_;
  double radius_;
  std::optional<double> half_length_;
};

}  // namespace mpm::geometry
