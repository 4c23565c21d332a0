//! Level-set loaders on OpenVDB: the only translation unit of libmpm that includes OpenVDB. It is
//! the plugin libmpm_openvdb.so of a shared build, a part of libmpm_core in a static one
//! (openvdb_plugin.h); either way libmpm_core reaches it through mpm_openvdb_plugin() alone.
//!   .vdb file  -> io::File, the first FloatGrid of class GRID_LEVEL_SET (or a named grid);
//!   mesh file  -> tools::meshToLevelSet on a linear transform of the caller's voxel size;
//!   phi(x)     -> tools::BoxSampler (trilinear) at the index-space position of x.
#include <mpm/core/error.h>
#include <mpm/core/number_text.h>
#include <mpm/geometry/triangle_mesh.h>

#include "level_set_grid.h"
#include "openvdb_plugin.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace mpm::geometry {

namespace {

//! Voxels along the longest side of a mesh beyond which the voxel size is taken for a unit
//! mistake (a mesh in millimetres): the narrow band alone would need gigabytes.
constexpr double kMaxVoxelsAcross = 10000.0;

double smallest_voxel_side(const openvdb::FloatGrid& grid) {
  const openvdb::Vec3d side = grid.voxelSize();
  return std::min({side.x(), side.y(), side.z()});
}

class VdbLevelSetGrid final : public detail::LevelSetGrid {
public:
  VdbLevelSetGrid(openvdb::FloatGrid::ConstPtr grid, const BoundingBox& box, std::string source)
      : LevelSetGrid(box, smallest_voxel_side(*grid), double(grid->background()), std::move(source)),
        grid_(std::move(grid)) {}

  double phi(const Vec<3>& x) const override {
    // The tree is fully loaded (no delayed loading) and never modified, so an unregistered
    // accessor per call is thread-safe.
    const auto accessor = grid_->getConstUnsafeAccessor();
    const openvdb::Vec3d index = grid_->transform().worldToIndex(openvdb::Vec3d(x[0], x[1], x[2]));
    return double(openvdb::tools::BoxSampler::sample(accessor, index));
  }

  void write_vdb(const std::string& file) const override {
    try {
      openvdb::io::File(file).write(openvdb::GridCPtrVec{grid_});
    } catch (const openvdb::Exception& e) {
      throw IoError(file + ": cannot write the level set: " + e.what());
    }
  }

private:
  openvdb::FloatGrid::ConstPtr grid_;
};

//! The grid behind a LevelSet, with the box around its narrow band.
std::shared_ptr<const detail::LevelSetGrid> make_grid(openvdb::FloatGrid::ConstPtr grid, const std::string& file) {
  const openvdb::CoordBBox band = grid->evalActiveVoxelBoundingBox();
  if (band.empty()) throw InputError(file + ": the level set has no active voxel (the obstacle is empty)");
  const openvdb::BBoxd world = grid->transform().indexToWorld(band);
  const BoundingBox box{Vec<3>(world.min().x(), world.min().y(), world.min().z()),
                        Vec<3>(world.max().x(), world.max().y(), world.max().z())};
  return std::make_shared<const VdbLevelSetGrid>(std::move(grid), box, file);
}

void require_readable(const std::string& file) {
  if (!std::ifstream(file)) throw InputError(file + ": cannot open the file");
}

std::shared_ptr<const detail::LevelSetGrid> grid_from_vdb(const std::string& file, const std::string& grid_name) {
  require_readable(file);
  openvdb::initialize();
  try {
    openvdb::io::File archive(file);
    archive.open(/*delayLoad=*/false);
    const openvdb::GridPtrVecPtr grids = archive.readAllGridMetadata();
    const auto is_float_level_set = [](const openvdb::GridBase& g) {
      return g.isType<openvdb::FloatGrid>() && g.getGridClass() == openvdb::GRID_LEVEL_SET;
    };
    std::string names;
    openvdb::GridBase::ConstPtr chosen;
    for (const openvdb::GridBase::Ptr& g : *grids) {
      names += (names.empty() ? "'" : ", '") + g->getName() + "' (" + g->valueType() + ", " +
               openvdb::GridBase::gridClassToString(g->getGridClass()) + ")";
      const bool wanted = grid_name.empty() ? is_float_level_set(*g) : g->getName() == grid_name;
      if (wanted && !chosen) chosen = g;
    }
    if (names.empty()) names = "none";
    if (!chosen)
      throw InputError(file + ": " +
                       (grid_name.empty() ? "no float level-set grid" : "no grid named '" + grid_name + "'") +
                       "; grids in the file: " + names);
    if (!is_float_level_set(*chosen))
      throw InputError(file + ": grid '" + grid_name + "' is no float level set; grids in the file: " + names);
    const openvdb::GridBase::Ptr grid = archive.readGrid(chosen->getName());
    archive.close();
    return make_grid(openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid), file);
  } catch (const openvdb::Exception& e) {
    throw InputError(file + ": cannot read the OpenVDB file: " + e.what());
  }
}

std::shared_ptr<const detail::LevelSetGrid> grid_from_mesh(const std::string& file, double voxel_size,
                                                           double half_width) {
  verify<InputError>(std::isfinite(voxel_size) && voxel_size > 0.0,
                     file + ": the voxel size must be > 0, got " + number_text(voxel_size));
  verify<InputError>(std::isfinite(half_width) && half_width >= 3.0,
                     file + ": the narrow band must be >= 3 voxels wide, got " + number_text(half_width));
  const TriangleMesh mesh = read_triangle_mesh(file);
  check_closed(mesh, file);  // an open surface has no inside to convert

  std::vector<openvdb::Vec3s> points;
  points.reserve(mesh.vertices.size());
  Vec<3> lo = mesh.vertices.front(), hi = mesh.vertices.front();
  for (const Vec<3>& x : mesh.vertices) {
    points.emplace_back(float(x[0]), float(x[1]), float(x[2]));
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double voxels_across = (hi - lo).maxCoeff() / voxel_size;
  verify<InputError>(voxels_across <= kMaxVoxelsAcross,
                     file + ": voxel size " + number_text(voxel_size) + " m gives " + number_text(voxels_across) +
                         " voxels across the mesh (at most " + number_text(kMaxVoxelsAcross) +
                         "); is the mesh in metres?");
  std::vector<openvdb::Vec3I> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);

  openvdb::initialize();
  const openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(voxel_size);
  openvdb::FloatGrid::Ptr grid =
      openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, float(half_width));
  grid->setName(std::filesystem::path(file).stem().string());
  return make_grid(grid, file);
}

}  // namespace

}  // namespace mpm::geometry

extern "C" const mpm::geometry::detail::OpenVdbPlugin* mpm_openvdb_plugin() {
  static const mpm::geometry::detail::OpenVdbPlugin plugin{
      mpm::geometry::detail::kOpenVdbPluginVersion, &mpm::geometry::grid_from_vdb, &mpm::geometry::grid_from_mesh};
  return &plugin;
}
