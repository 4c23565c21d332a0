list(APPEND FLUID_SOURCES
  src/solver/fluid_solver.cpp
  src/solver/projection_solver.cpp
  src/solver/weakly_compressible_solver.cpp
)
