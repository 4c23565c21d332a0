#pragma once
//! The velocity condition a collision obstacle imposes on a grid node inside it (Gao et al.
//! 2017, sec. 3.2 step 4; friction as in Stomakhin et al. 2013, sec. 8).
#include <mpm/core/types.h>

namespace mpm::geometry {

enum class ContactType {
  sticky,   //!< the node moves with the obstacle
  slip,     //!< the normal relative velocity is removed, the tangential one kept
  separate  //!< approaching nodes lose their normal relative velocity and feel Coulomb
            //!< friction; separating nodes are left free
};

//! What a contact acts on: a grid node, fixed in space, or a material point that moves with
//! the body (an enriched domain corner, domains/particle_domains.h). Slip contact holds a
//! node's normal velocity to the obstacle's, which is right for a node the obstacle sweeps
//! past but would glue a material point to an obstacle that moves away: a material point
//! takes slip contact as frictionless separating contact.
enum class ContactPoint { node, material };

struct Contact {
  ContactType type = ContactType::separate;
  double friction = 0.0;  //!< Coulomb coefficient mu >= 0 (used by `separate` only)

  //! The relative velocity v_rel = v - v_obstacle [m/s] after contact with the surface of unit
  //! outward normal n. For `separate` with v_n = v_rel . n < 0 and v_t = v_rel - v_n n:
  //!   v_rel <- 0                                  if |v_t| <= -mu v_n  (inside the friction cone)
  //!   v_rel <- v_t (1 + mu v_n / |v_t|)           otherwise (|v_t| reduced by mu |v_n|).
  //! A zero n (no direction known) leaves slip and separate contact without effect.
  template <int dim>
  Vec<dim> apply(const Vec<dim>& v_rel, const Vec<dim>& n, ContactPoint point = ContactPoint::node) const {
    if (point == ContactPoint::material && type == ContactType::slip)
      return Contact{ContactType::separate, 0.0}.apply<dim>(v_rel, n);
    switch (type) {
      case ContactType::sticky:
        return Vec<dim>::Zero();
      case ContactType::slip:
        return v_rel - v_rel.dot(n) * n;
      case ContactType::separate:
        break;
    }
    const double vn = v_rel.dot(n);
    if (vn >= 0.0) return v_rel;
    const Vec<dim> vt = v_rel - vn * n;
    const double vt_norm = vt.norm();
    if (vt_norm <= -friction * vn) return Vec<dim>::Zero();
    return vt * (1.0 + friction * vn / vt_norm);
  }
};

}  // namespace mpm::geometry
