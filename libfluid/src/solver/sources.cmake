list(APPEND FLUID_SOURCES
  src/solver/fluid_solver.cpp
  src/solver/projection_solver.cpp
)
