#pragma once
//! The sampled field behind mpm::geometry::LevelSet (private to libmpm). OpenVDB implements it in
//! level_set_vdb.cpp, the only translation unit that includes OpenVDB.
#include <mpm/geometry/level_set.h>

#include <string>
#include <utility>

namespace mpm::geometry::detail {

class LevelSetGrid {
public:
  LevelSetGrid(const BoundingBox& box, double voxel_size, double background, std::string source)
      : bounding_box_(box), voxel_size_(voxel_size), background_(background), source_(std::move(source)) {}
  virtual ~LevelSetGrid() = default;
  LevelSetGrid(const LevelSetGrid&) = delete;
  LevelSetGrid& operator=(const LevelSetGrid&) = delete;

  virtual double phi(const Vec<3>& x) const = 0;
  virtual void write_vdb(const std::string& file) const = 0;

  const BoundingBox& bounding_box() const { return bounding_box_; }
  double voxel_size() const { return voxel_size_; }
  double background() const { return background_; }
  const std::string& source() const { return source_; }

private:
  BoundingBox bounding_box_;
  double voxel_size_;
  double background_;
  std::string source_;
};

}  // namespace mpm::geometry::detail
