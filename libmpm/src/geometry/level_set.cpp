#include <mpm/geometry/level_set.h>

#include "level_set_grid.h"

namespace mpm::geometry {

LevelSet::LevelSet(std::shared_ptr<const detail::LevelSetGrid> grid) : grid_(std::move(grid)) {}

double LevelSet::phi(const Vec<3>& x) const { return grid_->phi(x); }

Vec<3> LevelSet::normal(const Vec<3>& x) const {
  return detail::normal_by_central_differences<3>([this](const Vec<3>& y) { return phi(y); }, x, grid_->voxel_size());
}

const BoundingBox& LevelSet::bounding_box() const { return grid_->bounding_box(); }
double LevelSet::voxel_size() const { return grid_->voxel_size(); }
double LevelSet::background() const { return grid_->background(); }
const std::string& LevelSet::source() const { return grid_->source(); }
void LevelSet::write_vdb(const std::string& file) const { grid_->write_vdb(file); }

}  // namespace mpm::geometry
