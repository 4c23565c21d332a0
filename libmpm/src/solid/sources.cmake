list(APPEND MPM_SOLID_SOURCES
  src/solid/material.cpp
  src/solid/solid_scene.cpp
  src/solid/solid_solver.cpp
  src/solid/rest_state.cpp
  src/solid/stages/stress_forces.cpp
  src/solid/stages/domain_transfer.cpp
  src/solid/stages/implicit_update.cpp
  src/solid/stages/return_map.cpp
)
