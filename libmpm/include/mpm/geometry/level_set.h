#pragma once
//! Collision obstacles given by a sampled signed distance field (a narrow-band level set).
//!
//! The grid is OpenVDB's, kept behind a pointer so that no public header includes OpenVDB.
//! A LevelSet is immutable and cheap to copy (copies share the grid); phi() and normal() may be
//! called from many threads at once.
#include <mpm/core/types.h>
#include <mpm/geometry/detail/central_difference.h>

#include <memory>
#include <string>
#include <utility>

namespace mpm::geometry {

namespace detail {
class LevelSetGrid;
}

//! An axis-aligned box [m].
struct BoundingBox {
  Vec<3> lo;
  Vec<3> hi;
};

class LevelSet {
public:
  //! The first float grid of class "level set" in a .vdb file, or the grid named `grid_name`.
  //! Throws InputError naming the file when it cannot be read or holds no such grid.
  static LevelSet from_vdb(const std::string& file, const std::string& grid_name = "");
  //! A closed triangle mesh (.obj, .stl; see read_triangle_mesh) converted to a level set of
  //! `voxel_size` [m] with a narrow band of `half_width` >= 3 voxels on either side of the surface.
  static LevelSet from_mesh(const std::string& file, double voxel_size, double half_width = 3.0);

  //! Signed distance [m], negative inside, by trilinear interpolation of the voxel values;
  //! beyond the narrow band it is -background() inside and +background() outside.
  double phi(const Vec<3>& x) const;
  //! Unit outward normal by central differences of phi with a step of one voxel; the zero
  //! vector beyond the narrow band, where phi is flat.
  Vec<3> normal(const Vec<3>& x) const;
  bool inside(const Vec<3>& x) const { return phi(x) < 0.0; }

  //! Box around the narrow band, so around the whole obstacle [m].
  const BoundingBox& bounding_box() const;
  double voxel_size() const;          //!< [m]
  double background() const;          //!< |phi| beyond the narrow band [m]
  const std::string& source() const;  //!< the file it was read from

  //! Writes the grid to a .vdb file (e.g. to convert a mesh once); throws IoError on failure.
  void write_vdb(const std::string& file) const;

private:
  explicit LevelSet(std::shared_ptr<const detail::LevelSetGrid> grid);
  std::shared_ptr<const detail::LevelSetGrid> grid_;
};

//! A level set as a collision shape of a `dim`-dimensional scene. A 2D scene sees the section of
//! the 3D obstacle by the plane z = slice_z; its normal is the in-plane gradient direction.
template <int dim>
class LevelSetShape {
public:
  explicit LevelSetShape(LevelSet level_set, double slice_z = 0.0)
      : level_set_(std::move(level_set)), slice_z_(slice_z) {}

  double phi(const Vec<dim>& x) const { return level_set_.phi(lift(x)); }
  Vec<dim> normal(const Vec<dim>& x) const {
    if constexpr (dim == 3) {
      return level_set_.normal(x);
    } else {
      return detail::normal_by_central_differences<dim>([this](const Vec<dim>& y) { return phi(y); }, x,
                                                        level_set_.voxel_size());
    }
  }
  bool inside(const Vec<dim>& x) const { return phi(x) < 0.0; }

  const LevelSet& level_set() const { return level_set_; }
  double slice_z() const { return slice_z_; }

private:
  Vec<3> lift(const Vec<dim>& x) const {
    if constexpr (dim == 3) {
      return x;
    } else {
      return {x[0], x[1], slice_z_};
    }
  }

  LevelSet level_set_;
  double slice_z_;
};

}  // namespace mpm::geometry
