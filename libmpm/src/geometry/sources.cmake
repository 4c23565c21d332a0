list(APPEND MPM_CORE_SOURCES
  src/geometry/triangle_mesh.cpp
  src/geometry/level_set.cpp
  src/geometry/collider.cpp
  src/geometry/collider_config.cpp
  src/geometry/seeding.cpp
  src/geometry/particle_spacing.cpp
  src/geometry/body_gap.cpp
  src/geometry/body_config.cpp
  src/geometry/flow_boundary_config.cpp
)
# OpenVDB is confined to level_set_vdb.cpp. A shared build compiles it into the plugin
# libmpm_openvdb.so, which mpm_core loads on the first level set (level_set_loader.cpp), so a
# process without level sets never maps OpenVDB. Without OpenVDB, the level-set loaders throw an
# InputError that says how to configure a build that has them.
if(NOT SEDIMENT_WITH_OPENVDB)
  list(APPEND MPM_CORE_SOURCES src/geometry/level_set_no_vdb.cpp)
elseif(BUILD_SHARED_LIBS)
  list(APPEND MPM_CORE_SOURCES src/geometry/level_set_loader.cpp)
  list(APPEND MPM_OPENVDB_PLUGIN_SOURCES src/geometry/level_set_vdb.cpp)
else()
  # A static mpm_core links OpenVDB in, as a plugin cannot share a static mpm_core.
  list(APPEND MPM_CORE_SOURCES src/geometry/level_set_loader.cpp src/geometry/level_set_vdb.cpp)
endif()
