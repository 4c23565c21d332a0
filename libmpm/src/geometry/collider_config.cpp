#include <mpm/geometry/collider_config.h>

#include <mpm/core/error.h>
#include <mpm/geometry/triangle_mesh.h>

#include <Eigen/Geometry>

#include <filesystem>
#include <string>
#include <vector>

namespace mpm::geometry {

namespace {

const std::vector<std::string> kContactNames{"sticky", "slip", "separate"};

ContactType contact_type(const std::string& name) {
  if (name == "sticky") return ContactType::sticky;
  if (name == "slip") return ContactType::slip;
  return ContactType::separate;
}

std::string contact_name(ContactType type) { return kContactNames[static_cast<std::size_t>(type)]; }

template <int dim>
Vec<dim> direction(const Config& c, const std::string& key) {
  const Vec<dim> v = c.vector<dim>(key);
  if (!(v.norm() > 0.0)) c.fail(key, "expected a nonzero vector");
  return v;
}

template <int dim>
Cylinder<dim> parse_cylinder(const Config& entry) {
  const Vec<dim> point = entry.vector<dim>("point");
  const double radius = entry.number("radius", Range::positive());
  if constexpr (dim == 2) {
    for (const char* key : {"axis", "half_length"})
      if (entry.has(key)) entry.fail(key, "a 2D cylinder is the disk of its radius: its axis is out of plane");
    return Cylinder<dim>(point, radius);
  } else {
    const Vec<dim> axis = direction<dim>(entry, "axis");
    std::optional<double> half_length;
    if (entry.has("half_length")) half_length = entry.number("half_length", Range::positive());
    return Cylinder<dim>(point, axis, radius, half_length);
  }
}

template <int dim>
Shape<dim> parse_shape(const Config& entry) {
  if (!entry.has("type")) entry.fail("type", "missing required key");
  const std::string type = entry.choice("type", "", {"half_space", "box", "sphere", "cylinder", "level_set"});
  if (type == "half_space") return HalfSpace<dim>(entry.vector<dim>("point"), direction<dim>(entry, "normal"));
  if (type == "box") {
    const Vec<dim> lo = entry.vector<dim>("lo"), hi = entry.vector<dim>("hi");
    if (!(hi.array() > lo.array()).all()) entry.fail("hi", "must exceed lo in every component");
    return Box<dim>(lo, hi);
  }
  if (type == "sphere") return Sphere<dim>(entry.vector<dim>("center"), entry.number("radius", Range::positive()));
  if (type == "cylinder") return parse_cylinder<dim>(entry);
  return parse_level_set<dim>(entry);
}

}  // namespace

Contact parse_contact(const Config& c) {
  const Contact contact{contact_type(c.choice("contact", "separate", kContactNames)),
                        c.number("friction", 0.0, Range::non_negative())};
  if (contact.friction > 0.0 && contact.type != ContactType::separate)
    c.fail("friction", "Coulomb friction applies to 'contact: separate' only");
  return contact;
}

template <int dim>
LevelSetShape<dim> parse_level_set(const Config& entry) {
  const std::string file = entry.text("file");
  const std::filesystem::path path = entry.input_file("file");

  double slice_z = 0.0;
  if constexpr (dim == 2) {
    slice_z = entry.number("slice_z", 0.0, Range::any());
  } else {
    if (entry.has("slice_z")) entry.fail("slice_z", "applies to 2D scenes only (the section plane z = slice_z)");
  }

  const bool is_mesh = is_triangle_mesh_file(file);
  if (!is_mesh && path.extension() != ".vdb") entry.fail("file", "unknown extension: expected .vdb, .obj or .stl");
  for (const char* key : {"voxel_size", "half_width"})
    if (!is_mesh && entry.has(key)) entry.fail(key, "applies to mesh files only; a .vdb file has its own voxels");
  if (is_mesh && entry.has("grid_name")) entry.fail("grid_name", "applies to .vdb files only");

  const double voxel_size = is_mesh ? entry.number("voxel_size", Range::positive()) : 0.0;
  const double half_width = is_mesh ? entry.number("half_width", 3.0, Range::closed(3.0, 1e308)) : 0.0;
  const std::string grid_name = is_mesh ? "" : entry.text("grid_name", "");
  try {
    LevelSet level_set = is_mesh ? LevelSet::from_mesh(path.string(), voxel_size, half_width)
                                 : LevelSet::from_vdb(path.string(), grid_name);
    return LevelSetShape<dim>(std::move(level_set), slice_z);
  } catch (const InputError& e) {
    // Only the loaders throw here: every key was read and validated above.
    entry.fail("file", e.what());
  }
}

template <int dim>
Collider<dim> parse_collider(const Config& entry) {
  Shape<dim> shape = parse_shape<dim>(entry);
  const Contact contact = parse_contact(entry);
  const Vec<dim> velocity = entry.vector<dim>("velocity", Vec<dim>::Zero());
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  if constexpr (dim == 2)
    omega[2] = entry.number("angular_velocity", 0.0, Range::any());
  else
    omega = entry.vector<3>("angular_velocity", Vec<3>::Zero());
  Collider<dim> collider(std::move(shape), contact, velocity);
  collider.set_hollow(entry.flag("hollow", false));
  if (entry.has("until")) collider.set_until(entry.number("until", Range::positive()));
  if (omega.isZero(0.0)) return collider;
  // The surface turns about the shape's own axis; the shape stays (it is symmetric about it).
  if (!velocity.isZero(0.0)) entry.fail("angular_velocity", "a turning collider cannot also translate (velocity)");
  Vec<dim> center;
  if (const auto* sphere = std::get_if<Sphere<dim>>(&collider.shape())) {
    center = sphere->center();
  } else if (const auto* cylinder = std::get_if<Cylinder<dim>>(&collider.shape())) {
    center = cylinder->point();
    if constexpr (dim == 3)
      if (omega.cross(cylinder->axis()).norm() > 1e-9 * omega.norm())
        entry.fail("angular_velocity", "a cylinder turns about its axis: the vector must be parallel to it");
  } else {
    entry.fail("angular_velocity", "only a sphere or a cylinder can turn in place (type: sphere or cylinder)");
  }
  collider.set_rotation(omega, center);
  return collider;
}

template <int dim>
DomainWalls<dim> parse_walls(const Config& walls, const Vec<dim>& domain_lo, const Vec<dim>& domain_hi,
                             double default_thickness) {
  verify<InputError>(default_thickness > 0.0, "domain walls: the default wall thickness must be > 0");
  const Contact contact = parse_contact(walls);
  const double half_extent = 0.5 * (domain_hi - domain_lo).minCoeff();
  const double thickness = walls.number("thickness", default_thickness, Range::open(0.0, half_extent));
  DomainWalls<dim> result(domain_lo, domain_hi, thickness, contact);
  for (int axis = 0; axis < dim; ++axis) {
    for (const Side side : {Side::lower, Side::upper}) {
      const std::string key = std::string(1, "xyz"[axis]) + (side == Side::lower ? "_min" : "_max");
      const std::string choice = walls.choice(key, contact_name(contact.type), {"sticky", "slip", "separate", "open"});
      if (choice == "open")
        result.set_wall(axis, side, std::nullopt);
      else
        result.set_wall(axis, side, Contact{contact_type(choice), contact.friction});
    }
  }
  return result;
}

template <int dim>
ColliderSet<dim> parse_colliders(const Config& scene, const Vec<dim>& domain_lo, const Vec<dim>& domain_hi,
                                 double default_wall_thickness) {
  ColliderSet<dim> colliders;
  for (const Config& entry : scene.list("colliders")) colliders.add(parse_collider<dim>(entry));
  if (const std::optional<Config> walls = scene.optional_child("walls"))
    colliders.set_walls(parse_walls<dim>(*walls, domain_lo, domain_hi, default_wall_thickness));
  return colliders;
}

template LevelSetShape<2> parse_level_set<2>(const Config&);
template LevelSetShape<3> parse_level_set<3>(const Config&);
template Collider<2> parse_collider<2>(const Config&);
template Collider<3> parse_collider<3>(const Config&);
template DomainWalls<2> parse_walls<2>(const Config&, const Vec<2>&, const Vec<2>&, double);
template DomainWalls<3> parse_walls<3>(const Config&, const Vec<3>&, const Vec<3>&, double);
template ColliderSet<2> parse_colliders<2>(const Config&, const Vec<2>&, const Vec<2>&, double);
template ColliderSet<3> parse_colliders<3>(const Config&, const Vec<3>&, const Vec<3>&, double);

}  // namespace mpm::geometry
