//! LevelSet loaders of a build without OpenVDB (SEDIMENT_WITH_OPENVDB=OFF): a scene that asks for
//! a level-set collider fails at load time with the reason.
#include <mpm/geometry/level_set.h>

#include <mpm/core/error.h>

namespace mpm::geometry {

namespace {

[[noreturn]] void no_openvdb(const std::string& file) {
  throw InputError(file +
                   ": a level-set obstacle needs OpenVDB, and this build has no OpenVDB "
                   "(configure with -DSEDIMENT_WITH_OPENVDB=ON)");
}

}  // namespace

LevelSet LevelSet::from_vdb(const std::string& file, const std::string&) { no_openvdb(file); }

LevelSet LevelSet::from_mesh(const std::string& file, double, double) { no_openvdb(file); }

}  // namespace mpm::geometry
