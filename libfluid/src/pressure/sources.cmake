list(APPEND FLUID_SOURCES
  src/pressure/cell_operator.cpp
  src/pressure/cg.cpp
  src/pressure/jacobi_pcg.cpp
  src/pressure/multigrid.cpp
  src/pressure/modulated_multigrid.cpp
  src/pressure/mgpcg.cpp
  src/pressure/cholmod.cpp
  src/pressure/hypre_runtime.cpp
  src/pressure/hypre_pfmg.cpp
  src/pressure/hypre_boomeramg.cpp
  src/pressure/null_space.cpp
  src/pressure/pressure_solver.cpp
  src/pressure/model_problems.cpp
)
