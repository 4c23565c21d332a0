//! Grid-node collision treatment (Gao et al. 2017, sec. 3.2 step 4), for a node x_i with
//! updated velocity v_i inside an obstacle moving at v_c:
//!   phi(x_i, t) = phi0(x_i - v_c t) <= 0   (phi0(x_i) for a fixed shape, Motion::fixed)
//!   v_i <- v_c + contact(v_i - v_c, n(x_i, t))      (contact.h: sticky, slip, separate + Coulomb)
#include <mpm/core/number_text.h>
#include <mpm/geometry/collider.h>

#include <mpm/core/error.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <string>

namespace mpm::geometry {

namespace {

void verify_friction(const Contact& contact) {
  verify<InputError>(std::isfinite(contact.friction) && contact.friction >= 0.0,
                     "collider: the friction coefficient must be >= 0, got " + number_text(contact.friction));
}

}  // namespace

template <int dim>
Collider<dim>::Collider(Shape<dim> shape, const Contact& contact, const Vec<dim>& velocity, Motion motion)
    : shape_(std::move(shape)), contact_(contact), velocity_(velocity), motion_(motion) {
  verify_friction(contact);
}

template <int dim>
void Collider<dim>::set_contact(const Contact& contact) {
  verify_friction(contact);
  contact_ = contact;
}

template <int dim>
Vec<dim> Collider<dim>::shape_position(const Vec<dim>& x, double t) const {
  return motion_ == Motion::translating ? Vec<dim>(x - t * velocity_) : x;
}

template <int dim>
double Collider<dim>::phi(const Vec<dim>& x, double t) const {
  if (t > until_) return std::numeric_limits<double>::infinity();
  const Vec<dim> x0 = shape_position(x, t);
  const double d = std::visit([&](const auto& shape) { return shape.phi(x0); }, shape_);
  return hollow_ ? -d : d;
}

template <int dim>
Vec<dim> Collider<dim>::normal(const Vec<dim>& x, double t) const {
  const Vec<dim> x0 = shape_position(x, t);
  const Vec<dim> n = std::visit([&](const auto& shape) { return shape.normal(x0); }, shape_);
  return hollow_ ? Vec<dim>(-n) : n;
}

template <int dim>
Vec<dim> Collider<dim>::velocity_at(const Vec<dim>& x) const {
  if (omega_.isZero(0.0)) return velocity_;
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  r.head<dim>() = x - center_;
  return velocity_ + omega_.cross(r).head<dim>();
}

template <int dim>
void Collider<dim>::project(const Vec<dim>& x, double t, Vec<dim>& v, ContactPoint point) const {
  if (phi(x, t) > 0.0) return;
  // A sticky node needs no normal, and the normal of a level set costs 2 dim samples.
  const Vec<dim> n = contact_.type == ContactType::sticky ? Vec<dim>::Zero() : normal(x, t);
  const Vec<dim> vc = velocity_at(x);
  v = vc + contact_.apply<dim>(Vec<dim>(v - vc), n, point);
}

namespace {
//! Appends the directions `contact` fixes for a relative velocity v_rel at a surface of unit
//! outward normal n.
template <int dim>
void contact_directions(const Contact& contact, const Vec<dim>& v_rel, const Vec<dim>& n, ContactPoint point,
                        std::vector<Vec<dim>>& fixed) {
  // A material point takes slip contact as separating contact (Contact::apply).
  const bool slip = contact.type == ContactType::slip && point == ContactPoint::node;
  if (contact.type == ContactType::sticky) {
    for (int a = 0; a < dim; ++a) fixed.push_back(Vec<dim>::Unit(a));
  } else if (slip || v_rel.dot(n) < 0.0) {
    fixed.push_back(n);
  }
}
}  // namespace

template <int dim>
void Collider<dim>::fixed_directions(const Vec<dim>& x, double t, const Vec<dim>& v, std::vector<Vec<dim>>& fixed,
                                     ContactPoint point) const {
  if (phi(x, t) > 0.0) return;
  const Vec<dim> n = contact_.type == ContactType::sticky ? Vec<dim>::Zero() : normal(x, t);
  contact_directions(contact_, Vec<dim>(v - velocity_at(x)), n, point, fixed);
}

template <int dim>
DomainWalls<dim>::DomainWalls(const Vec<dim>& lo, const Vec<dim>& hi, double thickness, const Contact& contact)
    : lo_(lo), hi_(hi), thickness_(thickness) {
  verify<InputError>((hi.array() > lo.array()).all(), "domain walls: hi must exceed lo in every component");
  verify<InputError>(std::isfinite(thickness) && thickness > 0.0,
                     "domain walls: the thickness must be > 0, got " + number_text(thickness));
  verify_friction(contact);
  walls_.fill(contact);
}

template <int dim>
void DomainWalls<dim>::set_wall(int axis, Side side, const std::optional<Contact>& contact) {
  verify<InputError>(0 <= axis && axis < dim, "domain walls: axis " + std::to_string(axis) + " out of range");
  if (contact) verify_friction(*contact);
  walls_[index(axis, side)] = contact;
}

template <int dim>
void DomainWalls<dim>::project(const Vec<dim>& x, Vec<dim>& v, ContactPoint point) const {
  const double layer = reach();
  for (int axis = 0; axis < dim; ++axis) {
    const std::optional<Contact>& lower = walls_[index(axis, Side::lower)];
    const std::optional<Contact>& upper = walls_[index(axis, Side::upper)];
    if (lower && x[axis] - lo_[axis] <= layer) v = lower->apply<dim>(v, Vec<dim>::Unit(axis), point);
    if (upper && hi_[axis] - x[axis] <= layer) v = upper->apply<dim>(v, Vec<dim>(-Vec<dim>::Unit(axis)), point);
  }
}

template <int dim>
bool DomainWalls<dim>::in_layer(const Vec<dim>& x) const {
  const double layer = reach();
  for (int axis = 0; axis < dim; ++axis)
    if ((walls_[index(axis, Side::lower)] && x[axis] - lo_[axis] <= layer) ||
        (walls_[index(axis, Side::upper)] && hi_[axis] - x[axis] <= layer))
      return true;
  return false;
}

template <int dim>
void DomainWalls<dim>::fixed_directions(const Vec<dim>& x, const Vec<dim>& v, std::vector<Vec<dim>>& fixed,
                                        ContactPoint point) const {
  const double layer = reach();
  for (int axis = 0; axis < dim; ++axis) {
    const std::optional<Contact>& lower = walls_[index(axis, Side::lower)];
    const std::optional<Contact>& upper = walls_[index(axis, Side::upper)];
    if (lower && x[axis] - lo_[axis] <= layer) contact_directions<dim>(*lower, v, Vec<dim>::Unit(axis), point, fixed);
    if (upper && hi_[axis] - x[axis] <= layer)
      contact_directions<dim>(*upper, v, Vec<dim>(-Vec<dim>::Unit(axis)), point, fixed);
  }
}

template <int dim>
bool ColliderSet<dim>::prescribes(const Vec<dim>& x, double t) const {
  for (const Collider<dim>& collider : colliders_)
    if (collider.phi(x, t) <= 0.0) return true;
  return walls_ && walls_->in_layer(x);
}

template <int dim>
Mat<dim> ColliderSet<dim>::free_directions(const Vec<dim>& x, double t, const Vec<dim>& v, ContactPoint point) const {
  std::vector<Vec<dim>> fixed;
  for (const Collider<dim>& collider : colliders_) collider.fixed_directions(x, t, v, fixed, point);
  if (walls_) walls_->fixed_directions(x, v, fixed, point);
  // Gram-Schmidt: an orthonormal basis Q of the fixed directions, then I - Q Q^T.
  Mat<dim> free = Mat<dim>::Identity();
  for (Vec<dim> d : fixed) {
    d = free * d;
    const double length = d.norm();
    if (length > 1e-9) free -= (d / length) * (d / length).transpose();
  }
  return free;
}

template <int dim>
void ColliderSet<dim>::project(const Vec<dim>& x, double t, Vec<dim>& v, ContactPoint point) const {
  for (const Collider<dim>& collider : colliders_) collider.project(x, t, v, point);
  if (walls_) walls_->project(x, v, point);
}

template <int dim>
bool ColliderSet<dim>::uses_level_sets() const {
  for (const Collider<dim>& collider : colliders_)
    if (collider.is_level_set()) return true;
  return false;
}

template class Collider<2>;
template class Collider<3>;
template class DomainWalls<2>;
template class DomainWalls<3>;
template class ColliderSet<2>;
template class ColliderSet<3>;

}  // namespace mpm::geometry
