#pragma once
//! What libmpm_core asks of OpenVDB (private to libmpm): the two level-set loaders of
//! level_set_vdb.cpp behind one C-linkage entry point. A shared build compiles them into the module
//! libmpm_openvdb.so, which level_set_loader.cpp loads on the first level set, so that a process
//! without level sets never maps libopenvdb; a static build links them into libmpm_core.
#include "level_set_grid.h"

#include <memory>
#include <string>

namespace mpm::geometry::detail {

//! Changes whenever OpenVdbPlugin or LevelSetGrid changes, so that a plugin of another build is
//! refused instead of being called through a different layout.
inline constexpr int kOpenVdbPluginVersion = 1;

struct OpenVdbPlugin {
  int version;  //!< kOpenVdbPluginVersion of the plugin's build; stays the first member
  std::shared_ptr<const LevelSetGrid> (*from_vdb)(const std::string& file, const std::string& grid_name);
  std::shared_ptr<const LevelSetGrid> (*from_mesh)(const std::string& file, double voxel_size, double half_width);
};

inline constexpr char kOpenVdbPluginEntryPoint[] = "mpm_openvdb_plugin";

}  // namespace mpm::geometry::detail

//! The entry point (named kOpenVdbPluginEntryPoint): the loaders, valid for the process lifetime.
extern "C" const mpm::geometry::detail::OpenVdbPlugin* mpm_openvdb_plugin();
