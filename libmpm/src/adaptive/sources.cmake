list(APPEND MPM_CORE_SOURCES
  src/adaptive/cell_tree.cpp
  src/adaptive/constrained_basis.cpp
  src/adaptive/adaptive_grid.cpp
  src/adaptive/adaptive_transfer.cpp
  src/adaptive/particle_levels.cpp
  src/adaptive/refinement.cpp
  src/adaptive/resampling.cpp
)
