list(APPEND FLUID_SOURCES
  src/stages/prescribed_nodes.cpp
  src/stages/pressure_projection.cpp
  src/stages/surface_velocity_extension.cpp
  src/stages/implicit_viscosity.cpp
  src/stages/equation_of_state.cpp
)
