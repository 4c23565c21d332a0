list(APPEND MPM_CORE_SOURCES
  src/geometry/triangle_mesh.cpp
  src/geometry/level_set.cpp
  src/geometry/collider.cpp
  src/geometry/collider_config.cpp
  src/geometry/seeding.cpp
  src/geometry/body_config.cpp
  src/geometry/flow_boundary_config.cpp
)
# OpenVDB is private to mpm_core and confined to level_set_vdb.cpp. Without it, the level-set
# loaders throw an InputError that says how to configure a build that has them.
if(SEDIMENT_WITH_OPENVDB)
  list(APPEND MPM_CORE_SOURCES src/geometry/level_set_vdb.cpp)
else()
  list(APPEND MPM_CORE_SOURCES src/geometry/level_set_no_vdb.cpp)
endif()
