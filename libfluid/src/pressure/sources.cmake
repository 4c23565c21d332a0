list(APPEND FLUID_SOURCES
  src/pressure/cell_operator.cpp
  src/pressure/cg.cpp
  src/pressure/jacobi_pcg.cpp
  src/pressure/multigrid.cpp
  src/pressure/modulated_multigrid.cpp
  src/pressure/mgpcg.cpp
  src/pressure/null_space.cpp
  src/pressure/pressure_solver.cpp
  src/pressure/model_problems.cpp
)
# The external back-ends, compiled only with their options (libfluid/CMakeLists.txt).
set(FLUID_HYPRE_SOURCES
  src/pressure/hypre_runtime.cpp
  src/pressure/hypre_pfmg.cpp
  src/pressure/hypre_boomeramg.cpp
)
set(FLUID_CHOLMOD_SOURCES
  src/pressure/cholmod.cpp
)
