list(APPEND FLUID_SOURCES
  src/pressure/cell_operator.cpp
)
